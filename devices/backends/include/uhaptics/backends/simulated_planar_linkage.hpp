#pragma once
// Simulated planar linkage (the RHI of paper 003 and the 3-DoF example): the lumped rigid-body
// dynamics of PlanarLinkageModel with joint friction (viscous + smoothed Coulomb), actuator torque
// saturation and a linear end-effector load standing in for the user's hand or a guide rail,
//
//   M(q) q_ddot + c(q, q_dot) + f(q_dot) + tau_stop(q, q_dot) = sat(tau_cmd) + J^T F_ext,
//   F_ext = bias + K (anchor - x) - B x_dot,
//
// with tau_stop a stiff one-sided spring-damper at the model's joint limits (mechanical stops),
// integrated at a fixed sub-step (default 0.1 ms) finer than the servo period, with a linearly
// implicit Euler step for the friction (stiff near zero velocity because of the Coulomb smoothing).
// step() is allocation-free and never throws.
#include "uhaptics/core/fault.hpp"
#include "uhaptics/models/planar_linkage_model.hpp"

namespace uhaptics {

/// Linear load at the end effector, evaluated at every sub-step.
struct EndEffectorLoad {
  Vec2 bias = Vec2::Zero();       // constant force [N]
  Vec2 anchor = Vec2::Zero();     // spring rest point [m]
  Mat2 stiffness = Mat2::Zero();  // [N/m]
  Mat2 damping = Mat2::Zero();    // [N s/m]
};

template <int N>
class SimulatedPlanarLinkage {
 public:
  using Model = PlanarLinkageModel<N>;
  using JointVector = Vec<N>;

  /// Throws uhaptics::Error when substep is not positive.
  explicit SimulatedPlanarLinkage(Model model, double substep = 1e-4);

  void reset(const JointVector& q, const JointVector& qd = JointVector::Zero()) noexcept;
  void setLoad(const EndEffectorLoad& load) noexcept { load_ = load; }

  /// Applies tau_command (saturated at the model's limits) for dt, rounded to whole sub-steps.
  /// Non-finite commands are replaced by zero and reported; the state stays finite.
  Fault step(const JointVector& tau_command, double dt) noexcept;

  double time() const noexcept { return t_; }
  const JointVector& position() const noexcept { return q_; }
  const JointVector& velocity() const noexcept { return qd_; }
  const JointVector& acceleration() const noexcept { return qdd_; }
  const JointVector& appliedTorque() const noexcept { return tau_applied_; }
  /// End-effector position, velocity and acceleration (task space) at the current state.
  Vec2 endEffectorPosition() const noexcept;
  Vec2 endEffectorVelocity() const noexcept;
  Vec2 endEffectorAcceleration() const noexcept { return xdd_; }
  const Vec2& externalForce() const noexcept { return f_ext_; }
  const Model& model() const noexcept { return model_; }

 private:
  void substep(double h) noexcept;
  void addStopTorque(JointVector& f) const noexcept;

  Model model_;
  double substep_;
  EndEffectorLoad load_;
  double t_ = 0.0;
  JointVector q_ = JointVector::Zero(), qd_ = JointVector::Zero(), qdd_ = JointVector::Zero();
  JointVector tau_applied_ = JointVector::Zero();
  Vec2 f_ext_ = Vec2::Zero(), xdd_ = Vec2::Zero();
};

extern template class SimulatedPlanarLinkage<3>;
extern template class SimulatedPlanarLinkage<4>;

}  // namespace uhaptics
