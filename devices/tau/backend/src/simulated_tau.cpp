#include "uhaptics/backends/simulated_tau.hpp"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>

#include "uhaptics/core/limits.hpp"

namespace uhaptics {

namespace {
// One-sided spring-damper per coordinate beyond +-half of the centre: pushes back, never pulls.
Vec3 stopForce(const Vec3& x, const Vec3& xd, double half, double stiffness, double damping) noexcept {
  Vec3 f = Vec3::Zero();
  for (int i = 0; i < 3; ++i) {
    const double beyond = x(i) - std::clamp(x(i), -half, half);
    if (beyond > 0.0) f(i) = std::min(0.0, -stiffness * beyond - damping * xd(i));
    if (beyond < 0.0) f(i) = std::max(0.0, -stiffness * beyond - damping * xd(i));
  }
  return f;
}
}  // namespace

SimulatedTau::SimulatedTau(const TauModel& model, const SimulatedTauOptions& options)
    : model_(model), options_(options), data_(model), rng_(options.seed) {
  if (options_.substeps == 0) options_.substeps = model.simulationSubsteps();
  if (options_.substeps < 1 || options_.substeps > 1000) throw Error("SimulatedTau: substeps must be in [1, 1000]");
  if (!(options_.period >= 0.0 && options_.period <= 0.1)) throw Error("SimulatedTau: period must be in [0, 0.1] s");
  if (options_.period == 0.0) options_.period = model.servoPeriod();
  if (options_.max_delay_samples < 0 || options_.max_delay_samples > 100)
    throw Error("SimulatedTau: max_delay_samples must be in [0, 100]");
  if (!(options_.tool_damping >= 0.0) || !(options_.tool_rotational_damping >= 0.0) || !(options_.hand.stiffness >= 0.0) ||
      !(options_.hand.damping >= 0.0))
    throw Error("SimulatedTau: damping and hand parameters must be >= 0");
  if (!(options_.relinearize_tolerance >= 0.0 && options_.relinearize_tolerance <= 0.1))
    throw Error("SimulatedTau: relinearize_tolerance must be in [0, 0.1] rad");
  command_history_.assign(static_cast<std::size_t>(options_.max_delay_samples) + 1, Vec6::Zero());
  reset(model.homeJoints());
}

void SimulatedTau::reset(const Vec6& q0) {
  q_ = q0;
  qd_.setZero();
  data_.pose = model_.homePose();
  if (model_.forward(q_, data_) != Fault::kNone) throw Error("SimulatedTau: forward kinematics fails at the start pose");
  for (auto& c : command_history_) c.setZero();
  history_head_ = 0;
  started_ = false;
  applied_.setZero();
  applied_delay_ = 0;
  hand_attached_ = false;
  hand_force_.setZero();
  time_ = 0.0;
  linearized_ = false;
  quantize();
}

void SimulatedTau::setHand(const Vec3& position, const Vec3& velocity, const Vec3& acceleration) noexcept {
  hand_attached_ = true;
  hand_p_ = position;
  hand_v_ = velocity;
  hand_a_ = acceleration;
}

void SimulatedTau::quantize() noexcept {
  if (!options_.quantize) {
    reading_ = q_;
    return;
  }
  const double res = model_.encoderResolution();
  for (int i = 0; i < 6; ++i) reading_(i) = std::floor(q_(i) / res) * res;
}

Fault SimulatedTau::linearize() noexcept {
  // data_ holds the forward kinematics at q_ from reset()/the previous step.
  const Fault f = model_.computeDynamicsTerms(q_, qd_, data_);
  if (f != Fault::kNone) return f;
  // The plant terms are frozen over the period, so the substeps only need M^-1 applied to the
  // drive and to the force directions: factorize and solve once, then matrix-vector products.
  mass_.compute(data_.M);
  const Mat<3, 6> Jp = data_.J.topRows<3>();
  const Mat<3, 6> Jr = data_.J.bottomRows<3>();
  force_to_qdd_ = mass_.solve(Jp.transpose());
  // Rotational damping: a generalized force -b Jr^T (Euler-angle rates), dissipative by construction.
  rotational_damping_ = -options_.tool_rotational_damping * mass_.solve(Jr.transpose()) * Jr;
  // The angular stops' torques on the orientation (Euler angles) act through Jr^T.
  if (options_.end_stops) torque_to_qdd_ = mass_.solve(Jr.transpose());
  q_lin_ = q_;
  pose_lin_ = data_.pose;
  linearized_ = true;
  return Fault::kNone;
}

Vec3 SimulatedTau::toolForce() const noexcept {
  const Eigen::PartialPivLU<Mat6> transpose(data_.J.transpose());
  const Vec6 wrench = transpose.solve(applied_ - data_.gravity);
  return wrench.allFinite() ? Vec3(wrench.head<3>()) : Vec3::Zero();
}

Fault SimulatedTau::step(const Vec6& tau_command, const Vec3& external_force) noexcept {
  // Transport delay: the plant applies the command issued d samples ago, d ~ U{0..max}.
  const Vec6 command = tau_command.allFinite() ? tau_command : Vec6::Zero();
  // The first command after reset() stands for the commands before the run (the device was held
  // at rest by the same controller), so a delayed plant does not start from a zero torque.
  if (!started_)
    for (Vec6& c : command_history_) c = command;
  started_ = true;
  history_head_ = (history_head_ + 1) % command_history_.size();
  command_history_[history_head_] = command;
  std::size_t delay = 0;
  if (options_.max_delay_samples > 0)
    delay = std::uniform_int_distribution<std::size_t>(0, static_cast<std::size_t>(options_.max_delay_samples))(rng_);
  applied_ = command_history_[(history_head_ + command_history_.size() - delay) % command_history_.size()];
  applied_delay_ = static_cast<int>(delay);
  clampSymmetric(applied_, model_.effortLimits());  // motor saturation

  if (!linearized_ || (q_ - q_lin_).cwiseAbs().maxCoeff() > options_.relinearize_tolerance) {
    const Fault f = linearize();
    if (f != Fault::kNone) return f;
  }
  const Mat<3, 6> Jp = data_.J.topRows<3>();
  const Mat<3, 6> Jr = data_.J.bottomRows<3>();
  const Vec3 p0 = data_.pose.head<3>();
  const Vec6 q0 = q_;
  const Vec6 qdd_drive = mass_.solve(applied_ - data_.bias - data_.gravity);
  const TauModel::EndStops& stops = model_.endStops();
  const Vec3 centre = model_.homePose().head<3>();
  const Vec3 a0 = data_.pose.tail<3>() - model_.homePose().tail<3>();
  const double T = options_.period;
  const double dt = T / options_.substeps;
  Vec6 q = q_, qd = qd_;
  Vec3 hand_sum = Vec3::Zero();
  for (int s = 0; s < options_.substeps; ++s) {
    const double t = s * dt;
    const Vec3 p = p0 + Jp * (q - q0);
    const Vec3 v = Jp * qd;
    Vec3 force = external_force - options_.tool_damping * v;
    if (hand_attached_) {
      const Vec3 hp = hand_p_ + hand_v_ * t + 0.5 * t * t * hand_a_;
      const Vec3 hv = hand_v_ + hand_a_ * t;
      const Vec3 fh = options_.hand.stiffness * (hp - p) + options_.hand.damping * (hv - v);
      hand_sum += fh;
      force += fh;
    }
    if (options_.end_stops) force += stopForce(p - centre, v, stops.half_side, stops.stiffness, stops.damping);
    Vec6 qdd = qdd_drive + force_to_qdd_ * force + rotational_damping_ * qd;
    if (options_.end_stops)
      qdd.noalias() += torque_to_qdd_ * stopForce(a0 + Jr * (q - q0), Jr * qd, stops.half_angle,
                                                 stops.angular_stiffness, stops.angular_damping);
    qd += dt * qdd;  // semi-implicit Euler: velocity first
    q += dt * qd;
  }
  if (!q.allFinite() || !qd.allFinite()) return Fault::kNonFiniteResult;
  hand_force_ = hand_sum / options_.substeps;
  if (hand_attached_) {
    hand_p_ += hand_v_ * T + 0.5 * T * T * hand_a_;
    hand_v_ += hand_a_ * T;
  }
  time_ += T;
  if (options_.relinearize_tolerance > 0.0 && (q - q_lin_).cwiseAbs().maxCoeff() <= options_.relinearize_tolerance) {
    // Within the held linearization the pose is still solved to the forward kinematics' tolerance:
    // Newton's method on the closure with dg/dX's factorization held from q_lin_, from the
    // first-order prediction (each step shrinks the error by dg/dX's relative change over the
    // travel, about the tolerance: one or two steps). What does not converge takes the full solve.
    Vec6 pose = pose_lin_, g;
    pose.noalias() += data_.J * (q - q_lin_);
    bool converged = false;
    for (int it = 0;; ++it) {
      model_.kinematics().closure(pose, q, g);
      converged = g.cwiseAbs().maxCoeff() <= model_.fkTolerance();  // false for NaN
      if (converged || it == 3) break;
      pose.noalias() -= data_.lu.solve(g);
    }
    if (converged) {
      data_.pose = pose;
      q_ = q;
      qd_ = qd;
      quantize();
      return Fault::kNone;
    }
  }
  // Keep pose/J current for observers, Newton warm-started from the first-order prediction
  // X + J dq (usually one iteration).
  linearized_ = false;
  const Vec6 pose_before = data_.pose;
  data_.pose.noalias() += data_.J * (q - q0);
  const Fault f = model_.forward(q, data_);
  if (f != Fault::kNone) {
    // No assembly at q: the mechanism cannot get there. It stops where it was; pose() and J are
    // solved again at q_ (forward() used them as scratch), from the solution they had.
    data_.pose = pose_before;
    qd_.setZero();
    if (model_.forward(q_, data_) != Fault::kNone) data_.pose = pose_before;
    return f;
  }
  q_ = q;
  qd_ = qd;
  quantize();
  return f;
}

}  // namespace uhaptics
