#include "bridge.hpp"

#include <pinocchio/algorithm/rnea.hpp>

namespace latentoc {

std::string build_rnea(const BridgeModel& m) {
  ADData data(m.ad_model);
  SX q = SX::sym("q", m.nq()), v = SX::sym("v", m.nv()), a = SX::sym("a", m.nv());
  pinocchio::rnea(m.ad_model, data, to_eigen(q), to_eigen(v), to_eigen(a));
  return ::casadi::Function("rnea", {q, v, a}, {to_sx(data.tau)}, {"q", "v", "a"}, {"tau"}).serialize();
}

}  // namespace latentoc
