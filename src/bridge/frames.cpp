#include "bridge.hpp"

#include <pinocchio/algorithm/frames.hpp>
#include <pinocchio/algorithm/kinematics.hpp>

namespace latentoc {

std::string build_frame_placement(const BridgeModel& m, const std::string& frame) {
  const auto fid = m.frame_id(frame);
  ADData data(m.ad_model);
  SX q = SX::sym("q", m.nq());
  pinocchio::framesForwardKinematics(m.ad_model, data, to_eigen(q));
  const auto& oMf = data.oMf[fid];
  return ::casadi::Function("frame_placement_" + frame, {q}, {to_sx(oMf.translation()), to_sx(oMf.rotation())},
                            {"q"}, {"translation", "rotation"})
      .serialize();
}

std::string build_frame_velocity(const BridgeModel& m, const std::string& frame) {
  const auto fid = m.frame_id(frame);
  ADData data(m.ad_model);
  SX q = SX::sym("q", m.nq()), v = SX::sym("v", m.nv());
  pinocchio::forwardKinematics(m.ad_model, data, to_eigen(q), to_eigen(v));
  const auto vel = pinocchio::getFrameVelocity(m.ad_model, data, fid, pinocchio::LOCAL_WORLD_ALIGNED);
  return ::casadi::Function("frame_velocity_" + frame, {q, v}, {to_sx(vel.toVector())}, {"q", "v"}, {"velocity"})
      .serialize();
}

std::string build_frame_jacobian(const BridgeModel& m, const std::string& frame) {
  const auto fid = m.frame_id(frame);
  ADData data(m.ad_model);
  SX q = SX::sym("q", m.nq());
  ADData::Matrix6x J(6, m.nv());
  J.setZero();
  pinocchio::computeFrameJacobian(m.ad_model, data, to_eigen(q), fid, pinocchio::LOCAL_WORLD_ALIGNED, J);
  return ::casadi::Function("frame_jacobian_" + frame, {q}, {to_sx(J)}, {"q"}, {"J"}).serialize();
}

}  // namespace latentoc
