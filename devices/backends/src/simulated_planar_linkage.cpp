#include "uhaptics/backends/simulated_planar_linkage.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>

#include "uhaptics/core/limits.hpp"

namespace uhaptics {

template <int N>
SimulatedPlanarLinkage<N>::SimulatedPlanarLinkage(Model model, double substep)
    : model_(std::move(model)), substep_(substep) {
  if (!(substep > 0.0) || !std::isfinite(substep)) throw Error("simulated planar linkage: substep must be positive");
  reset(model_.homeJoints());
}

template <int N>
void SimulatedPlanarLinkage<N>::reset(const JointVector& q, const JointVector& qd) noexcept {
  q_ = q;
  qd_ = qd;
  qdd_.setZero();
  tau_applied_.setZero();
  f_ext_.setZero();
  xdd_.setZero();
  t_ = 0.0;
}

template <int N>
Vec2 SimulatedPlanarLinkage<N>::endEffectorPosition() const noexcept {
  Vec2 x;
  model_.forward(q_, x);
  return x;
}

template <int N>
Vec2 SimulatedPlanarLinkage<N>::endEffectorVelocity() const noexcept {
  Mat<2, N> J;
  model_.jacobian(q_, J);
  return J * qd_;
}

template <int N>
Fault SimulatedPlanarLinkage<N>::step(const JointVector& tau_command, double dt) noexcept {
  Fault fault = Fault::kNone;
  tau_applied_ = tau_command;
  if (zeroIfNonFinite(tau_applied_) != Fault::kNone) fault = Fault::kNonFiniteInput;
  clampSymmetric(tau_applied_, model_.effortLimits());  // the amplifiers saturate
  const long n = std::max(1L, std::lround(dt / substep_));
  const double h = dt > 0.0 && std::isfinite(dt) ? dt / static_cast<double>(n) : substep_;
  for (long i = 0; i < n; ++i) substep(h);
  return fault;
}

// Mechanical stops at the model's joint limits: beyond a bound the limited coordinate s_j = C_j q
// meets a stiff spring-damper that only pushes back (assumed: 100 N m/rad, 0.5 N m s/rad, a rubber
// bumper; stable at the 0.1 ms sub-step for the RHI's smallest joint inertia). Added to the
// resistive torque f.
template <int N>
void SimulatedPlanarLinkage<N>::addStopTorque(JointVector& f) const noexcept {
  constexpr double kStopStiffness = 100.0, kStopDamping = 0.5;
  const JointLimits<N>& l = model_.jointLimits();
  if (!l.any()) return;
  const JointVector s = l.map * q_, sd = l.map * qd_;
  for (int j = 0; j < N; ++j) {
    double push = 0.0;  // generalized force on s_j
    if (s(j) < l.lower(j)) push = std::max(0.0, kStopStiffness * (l.lower(j) - s(j)) - kStopDamping * sd(j));
    else if (s(j) > l.upper(j)) push = std::min(0.0, -kStopStiffness * (s(j) - l.upper(j)) - kStopDamping * sd(j));
    if (push != 0.0) f.noalias() -= push * l.map.row(j).transpose();
  }
}

template <int N>
void SimulatedPlanarLinkage<N>::substep(double h) noexcept {
  Mat<2, N> J;
  Vec2 x;
  model_.jacobian(q_, J);
  model_.forward(q_, x);
  const Vec2 xd = J * qd_;
  f_ext_ = load_.bias + load_.stiffness * (load_.anchor - x) - load_.damping * xd;

  Mat<N, N> M;
  JointVector c, f, dfdqd;
  model_.massMatrix(q_, M);
  model_.velocityProductTorque(q_, qd_, c);
  model_.frictionTorque(qd_, f, &dfdqd);
  addStopTorque(f);
  // (M + h D) qd' = M qd + h (tau + J^T F - c - f(qd) + D qd), D = df/dqd, plus the load damping
  // reflected to the joints (J^T B J), both treated implicitly for stability at any sub-step.
  Mat<N, N> D = dfdqd.asDiagonal();
  const JointVector rhs =
      M * qd_ + h * (tau_applied_ + J.transpose() * (f_ext_ + load_.damping * xd) - c - f + D * qd_);
  D.noalias() += J.transpose() * load_.damping * J;
  const Mat<N, N> A = M + h * D;
  const JointVector qd_next = Eigen::LLT<Mat<N, N>>(A).solve(rhs);
  const Vec2 xd_prev = xd;
  qdd_ = (qd_next - qd_) / h;
  qd_ = qd_next;
  q_ += h * qd_;
  t_ += h;
  Mat<2, N> J_next;
  model_.jacobian(q_, J_next);
  xdd_ = (J_next * qd_ - xd_prev) / h;
}

template class SimulatedPlanarLinkage<3>;
template class SimulatedPlanarLinkage<4>;

}  // namespace uhaptics
