#include "bridge.hpp"

#include <pinocchio/algorithm/aba.hpp>

namespace latentoc {

std::string build_aba(const BridgeModel& m) {
  ADData data(m.ad_model);
  SX q = SX::sym("q", m.nq()), v = SX::sym("v", m.nv()), tau = SX::sym("tau", m.nv());
  pinocchio::aba(m.ad_model, data, to_eigen(q), to_eigen(v), to_eigen(tau));
  return ::casadi::Function("aba", {q, v, tau}, {to_sx(data.ddq)}, {"q", "v", "tau"}, {"a"}).serialize();
}

}  // namespace latentoc
