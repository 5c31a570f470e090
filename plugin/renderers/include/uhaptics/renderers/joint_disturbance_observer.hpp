#pragma once
// Steady-state Kalman observer of a linearized 6-joint plant with an input disturbance: estimates
// the joint velocity qdot, the joint position q and a disturbance torque d from the encoders. Joint
// velocity cannot be differentiated from 4096-count encoders (one count per servo period is
// 1.5 rad/s, which the LQR's velocity gain would turn into newton-metres of noise); d is the user's
// force through J^T, modelled as a random walk, so that a steady push does not bias the velocity
// estimate. Servo-rate, allocation-free. Designed by designLqrWall (tau_wall_design.hpp).
#include "uhaptics/core/types.hpp"

namespace uhaptics {

class JointDisturbanceObserver {
 public:
  /// The plant linearized at (joints, torque): x = (qdot, q - joints, d),
  /// x+ = A x + B (u - torque), y = q - joints.
  struct Gains {
    Vec6 joints = Vec6::Zero();
    Vec6 torque = Vec6::Zero();
    Mat<18, 18> A = Mat<18, 18>::Zero();
    Mat<18, 6> B = Mat<18, 6>::Zero();
    Mat<18, 6> gain = Mat<18, 6>::Zero();  // current-estimate Kalman gain
  };

  explicit JointDisturbanceObserver(const Gains& gains) : gains_(gains) {}
  void setGains(const Gains& gains) noexcept { gains_ = gains; }
  /// At rest at the measured joints, no disturbance.
  void reset(const Vec6& q_measured) noexcept {
    estimate_.setZero();
    estimate_.segment<6>(6) = q_measured - gains_.joints;
  }
  /// One servo period: predicted with the torque [N m] that acted over it, corrected with the new
  /// measurement q_measured [rad]. Estimates: velocity() [rad/s], position() [rad], disturbance()
  /// [N m].
  void update(const Vec6& q_measured, const Vec6& acting) noexcept {
    const Vec<18> predicted = gains_.A * estimate_ + gains_.B * (acting - gains_.torque);
    const Vec6 innovation = q_measured - gains_.joints - predicted.segment<6>(6);
    estimate_ = predicted + gains_.gain * innovation;
  }
  Vec6 velocity() const noexcept { return estimate_.head<6>(); }
  Vec6 position() const noexcept { return gains_.joints + estimate_.segment<6>(6); }
  Vec6 disturbance() const noexcept { return estimate_.tail<6>(); }
  const Gains& gains() const noexcept { return gains_; }

 private:
  Gains gains_;
  Vec<18> estimate_ = Vec<18>::Zero();
};

}  // namespace uhaptics
