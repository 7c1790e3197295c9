#include "bridge.hpp"

#include <pinocchio/algorithm/centroidal.hpp>

namespace latentoc {

std::string build_centroidal_momentum(const BridgeModel& m) {
  ADData data(m.ad_model);
  SX q = SX::sym("q", m.nq()), v = SX::sym("v", m.nv());
  pinocchio::computeCentroidalMomentum(m.ad_model, data, to_eigen(q), to_eigen(v));
  return ::casadi::Function("centroidal_momentum", {q, v}, {to_sx(data.hg.toVector())}, {"q", "v"}, {"h"})
      .serialize();
}

std::string build_centroidal_momentum_rate(const BridgeModel& m) {
  ADData data(m.ad_model);
  SX q = SX::sym("q", m.nq()), v = SX::sym("v", m.nv()), a = SX::sym("a", m.nv());
  pinocchio::computeCentroidalMomentumTimeVariation(m.ad_model, data, to_eigen(q), to_eigen(v), to_eigen(a));
  return ::casadi::Function("centroidal_momentum_rate", {q, v, a}, {to_sx(data.dhg.toVector())},
                            {"q", "v", "a"}, {"dh"})
      .serialize();
}

}  // namespace latentoc
