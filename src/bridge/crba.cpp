#include "bridge.hpp"

#include <pinocchio/algorithm/crba.hpp>

namespace latentoc {

std::string build_mass_matrix(const BridgeModel& m) {
  ADData data(m.ad_model);
  SX q = SX::sym("q", m.nq());
  pinocchio::crba(m.ad_model, data, to_eigen(q));
  // crba fills the upper triangle; mirror it.
  ADMatrix M = data.M;
  for (int i = 0; i < m.nv(); ++i)
    for (int j = 0; j < i; ++j) M(i, j) = M(j, i);
  return ::casadi::Function("mass_matrix", {q}, {to_sx(M)}, {"q"}, {"M"}).serialize();
}

}  // namespace latentoc
