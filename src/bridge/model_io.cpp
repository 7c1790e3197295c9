// Reading the numeric model from its text serialization and casting it to SX.
#include "bridge.hpp"

#include <pinocchio/serialization/model.hpp>

#include <stdexcept>

namespace latentoc {

BridgeModel::BridgeModel(const std::string& serialized) {
  try {
    model.loadFromString(serialized);
  } catch (const std::exception& e) {
    throw std::invalid_argument(std::string("could not read the serialized pinocchio.Model: ") + e.what());
  }
  for (std::size_t j = 1; j < model.joints.size(); ++j) {
    const std::string shortname = model.joints[j].shortname();
    if (shortname.find("Composite") != std::string::npos || shortname.find("Mimic") != std::string::npos)
      throw std::invalid_argument("joint '" + model.names[j] + "' has type " + shortname +
                                  ", which the latentoc bridge does not handle");
  }
  ad_model = model.cast<SX>();
}

int BridgeModel::nq() const { return model.nq; }
int BridgeModel::nv() const { return model.nv; }

std::size_t BridgeModel::frame_id(const std::string& name) const {
  if (!model.existFrame(name)) throw std::invalid_argument("unknown frame name '" + name + "'");
  return model.getFrameId(name);
}

}  // namespace latentoc
