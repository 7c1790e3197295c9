#include "bridge.hpp"

#include <pinocchio/algorithm/joint-configuration.hpp>

namespace latentoc {

std::string build_integrate(const BridgeModel& m) {
  SX q = SX::sym("q", m.nq()), dv = SX::sym("dv", m.nv());
  ADVector out(m.nq());
  pinocchio::integrate(m.ad_model, to_eigen(q), to_eigen(dv), out);
  return ::casadi::Function("integrate", {q, dv}, {to_sx(out)}, {"q", "dv"}, {"q_next"}).serialize();
}

std::string build_difference(const BridgeModel& m) {
  SX q0 = SX::sym("q0", m.nq()), q1 = SX::sym("q1", m.nq());
  ADVector out(m.nv());
  pinocchio::difference(m.ad_model, to_eigen(q0), to_eigen(q1), out);
  return ::casadi::Function("difference", {q0, q1}, {to_sx(out)}, {"q0", "q1"}, {"dv"}).serialize();
}

}  // namespace latentoc
