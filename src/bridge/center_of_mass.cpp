#include "bridge.hpp"

#include <pinocchio/algorithm/center-of-mass.hpp>

namespace latentoc {

std::string build_com(const BridgeModel& m) {
  ADData data(m.ad_model);
  SX q = SX::sym("q", m.nq());
  pinocchio::centerOfMass(m.ad_model, data, to_eigen(q), false);
  return ::casadi::Function("com", {q}, {to_sx(data.com[0])}, {"q"}, {"com"}).serialize();
}

}  // namespace latentoc
