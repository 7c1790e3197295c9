// latentoc bridge: Pinocchio's templated algorithms instantiated on casadi::SX.
// Each algorithm lives in its own translation unit so the build runs in parallel.
#pragma once

#include <casadi/casadi.hpp>
#include <pinocchio/autodiff/casadi.hpp>
#include <pinocchio/multibody/model.hpp>
#include <pinocchio/multibody/data.hpp>

#include <string>
#include <vector>

namespace latentoc {

using SX = ::casadi::SX;
using ADModel = pinocchio::ModelTpl<SX>;
using ADData = pinocchio::DataTpl<SX>;
using ADVector = Eigen::Matrix<SX, Eigen::Dynamic, 1>;
using ADMatrix = Eigen::Matrix<SX, Eigen::Dynamic, Eigen::Dynamic>;

// A numeric model read from pinocchio.Model.saveToString() and its SX cast.
struct BridgeModel {
  explicit BridgeModel(const std::string& serialized);
  int nq() const;
  int nv() const;
  std::size_t frame_id(const std::string& name) const;  // throws std::invalid_argument

  pinocchio::Model model;
  ADModel ad_model;
};

// Eigen <-> SX helpers.
inline ADVector to_eigen(const SX& s) {
  ADVector out(s.size1());
  for (casadi_int i = 0; i < s.size1(); ++i) out[i] = s(i);
  return out;
}

template <typename Derived>
inline SX to_sx(const Eigen::MatrixBase<Derived>& m) {
  SX out = SX::zeros(m.rows(), m.cols());
  for (Eigen::Index i = 0; i < m.rows(); ++i)
    for (Eigen::Index j = 0; j < m.cols(); ++j) out(i, j) = m(i, j);
  return out;
}

// Each returns a serialized casadi::Function (casadi.Function.deserialize on the Python side).
std::string build_rnea(const BridgeModel& m);
std::string build_com(const BridgeModel& m);
std::string build_centroidal_momentum(const BridgeModel& m);
std::string build_centroidal_momentum_rate(const BridgeModel& m);
std::string build_frame_placement(const BridgeModel& m, const std::string& frame);
std::string build_frame_velocity(const BridgeModel& m, const std::string& frame);
std::string build_frame_jacobian(const BridgeModel& m, const std::string& frame);
std::string build_mass_matrix(const BridgeModel& m);
std::string build_integrate(const BridgeModel& m);
std::string build_difference(const BridgeModel& m);

}  // namespace latentoc
