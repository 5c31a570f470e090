#pragma once
// Servo-rate renderers for underactuated devices (paper 000), generic over any KinematicModel:
//
//   StandardRenderer<M>             tau_a = S J^T Z_x (x_p - f(q))                    (eq. 1)
//   NullSpaceRenderer<M>            tau_a = S J^T P_n Z_x (x_p - f(q))                (eq. 4)
//   LinearizedSubspaceRenderer<M>   tau_a = Z_q S dq, dq = argmin |x_p - f(q) - J dq| (eq. 7-8)
//   NonlinearSubspaceRenderer<M>    tau_a = Z_q S (q* - q), q* = argmin |x_p - f(q*)| (eq. 6)
//
// Use: construct once (set-up: validates gains, throws uhaptics::Error), then every servo period
//
//   Fault f = renderer.tick(q, x_proxy, tau_a);   // never throws, never allocates
//
// q is the sensed device state (actuated and sensed-only joints), x_proxy the proxy the environment
// computed in the task space. A CHAI3D adapter that has a Cartesian proxy force F instead passes
// x_proxy = f(q) + Z_x^-1 F (the force read back as a displacement through the coupling stiffness).
// On any fault tau_a is zero (a state the model flags outside its working range, when the model
// offers inWorkingRange(), is Fault::kOutOfRange). Otherwise tau_a is finite and inside +-force_limit (clamped per
// actuator; `last().clamped` says so). `last()` holds the diagnostics of the latest tick (probe,
// Jacobian, deviation, solver report); `displayedImpedance()` evaluates the method's theoretical
// d tau / d q (eq. 2, 5, 9) at the latest tick's Jacobian, outside the servo path.
//
// Singular configurations: inverses are damped least squares (core regularizedSolve, damping from
// s_min / s_max < 1e-3 by default), so commands stay bounded through ill-conditioning. A non-finite
// Jacobian is Fault::kSingular for every method; where J itself is inverted (linearized subspace),
// s_min / s_max below `singular_threshold` (1e-9: rank lost, not just ill-conditioned) is too, and
// the nonlinear solve reports Fault::kNotConverged (it accepts only undamped final steps). The
// transpose-based baselines stay finite and bounded without a fault.
#include <limits>
#include <string>

#include "uhaptics/core/decompositions.hpp"
#include "uhaptics/core/fault.hpp"
#include "uhaptics/core/kinematic_model.hpp"
#include "uhaptics/core/limits.hpp"
#include "uhaptics/core/model_capabilities.hpp"
#include "uhaptics/core/subspace_proxy_solver.hpp"
#include "uhaptics/core/underactuated.hpp"

namespace uhaptics {

/// Gains and limits shared by the four renderers (Z_x is used by standard / null-space, Z_q by the
/// subspace methods; both are validated so one settings object serves every method).
template <class Model>
struct UnderactuatedGains {
  static constexpr int T = Model::kTask, A = Model::kActuated;
  Mat<T, T> Zx = Mat<T, T>::Identity();  // task-space stiffness (symmetric, positive semi-definite)
  Mat<A, A> Zq = Mat<A, A>::Identity();  // actuator-space stiffness (symmetric, positive semi-definite)
  Vec<A> force_limit = Vec<A>::Constant(std::numeric_limits<double>::infinity());
  RegularizationOptions regularization{};
  double singular_threshold = 1e-9;  // s_min / s_max below this: Fault::kSingular
};

/// What the latest tick computed (for logging, plots and the CHAI3D adapter's visual proxy).
template <class Model>
struct UnderactuatedDiagnostics {
  static constexpr int T = Model::kTask, N = Model::kJoints, A = Model::kActuated;
  Vec<T> probe = Vec<T>::Zero();          // f(q)
  Mat<T, N> J = Mat<T, N>::Zero();
  Vec<N> joint_deviation = Vec<N>::Zero();  // subspace methods: dq (linearized) or q* - q
  Vec<N> subspace_proxy = Vec<N>::Zero();   // subspace methods: q + joint deviation
  Vec<A> unclamped = Vec<A>::Zero();        // command before the force limit
  RegularizedSolveInfo solve{};             // conditioning of the last linear solve
  SubspaceSolveReport nonlinear{};          // nonlinear method only
  bool clamped = false;
  bool free_space = false;  // proxy on the probe: zero command without any solve
  Fault fault = Fault::kNone;
};

namespace detail {
template <int R>
void requireSymmetricPsd(const Mat<R, R>& Z, const char* name) {
  if (!Z.allFinite()) throw Error(std::string(name) + " has non-finite entries");
  if (!Z.isApprox(Z.transpose(), 1e-12) && !(Z - Z.transpose()).isZero(1e-12))
    throw Error(std::string(name) + " must be symmetric");
  Vec<R> lambda;
  if (!symmetricEigen(Z, lambda)) throw Error(std::string(name) + ": its eigenvalues cannot be computed");
  if (lambda.minCoeff() < -1e-12 * std::max(1.0, lambda.cwiseAbs().maxCoeff()))
    throw Error(std::string(name) + " must be positive semi-definite (a negative stiffness is active)");
}
}  // namespace detail

/// The checks, clamping and fault handling every method shares; Derived supplies
///   Fault computeCommand(const JointVector& q, const TaskVector& dx, ActuatorVector& tau) noexcept
///   Mat<N, N> theoreticalImpedance() const
template <class Model, class Derived>
class UnderactuatedRendererBase {
  static_assert(kIsKinematicModel<Model>, "renderers need a KinematicModel");

 public:
  static constexpr int T = Model::kTask, N = Model::kJoints, A = Model::kActuated;
  using JointVector = Vec<N>;
  using TaskVector = Vec<T>;
  using ActuatorVector = Vec<A>;
  using Gains = UnderactuatedGains<Model>;
  using Diagnostics = UnderactuatedDiagnostics<Model>;

  /// Keeps a reference to model (it must outlive the renderer). Throws Error on invalid gains.
  UnderactuatedRendererBase(const Model& model, const Gains& gains) : model_(model), gains_(gains) {
    const auto& S = model.selection();
    if (!underactuated::isSelection<A, N>(S))
      throw Error("the model's selection() must pick distinct joints (rows of the identity)");
    Sn_ = underactuated::complementSelection<A, N>(S);
    detail::requireSymmetricPsd<T>(gains.Zx, "Z_x");
    detail::requireSymmetricPsd<A>(gains.Zq, "Z_q");
    if (!(gains.force_limit.array() > 0.0).all() || gains.force_limit.hasNaN())
      throw Error("force_limit must be positive for every actuator");
    if (!(gains.regularization.epsilon > 0.0 && gains.regularization.epsilon < 1.0 &&
          gains.regularization.lambda_max > 0.0 && gains.regularization.lambda_max < 1.0))
      throw Error("regularization: epsilon and lambda_max must lie in (0, 1)");
    if (!(gains.singular_threshold >= 0.0 && gains.singular_threshold < gains.regularization.epsilon))
      throw Error("singular_threshold must lie in [0, regularization.epsilon)");
  }

  /// One servo period: tau_a for device state q and proxy x_proxy. Zero tau_a on any fault.
  Fault tick(const JointVector& q, const TaskVector& x_proxy, ActuatorVector& tau_a) noexcept {
    return tickFrom(
        q, x_proxy, tau_a,
        [&] {
          if constexpr (kHasWorkingRange<Model>) return model_.inWorkingRange(q);
          return true;
        },
        [&](TaskVector& probe) { model_.forward(q, probe); }, [&](Mat<T, N>& J) { model_.jacobian(q, J); });
  }
  /// The same tick from the kinematics the caller already evaluated at q, for a caller that keeps
  /// them anyway (a device's sensed state): probe = f(q), J = df/dq and in_range = the model's
  /// inWorkingRange(q) (true for a model without one). The model is then evaluated only by a solve.
  Fault tick(const JointVector& q, const TaskVector& x_proxy, const TaskVector& probe, const Mat<T, N>& J,
             bool in_range, ActuatorVector& tau_a) noexcept {
    return tickFrom(
        q, x_proxy, tau_a, [in_range] { return in_range; }, [&](TaskVector& x) { x = probe; },
        [&](Mat<T, N>& J_out) { J_out = J; });
  }

  /// Theoretical displayed impedance d tau / d q (N x N, tau = S^T tau_a) at the latest tick.
  Mat<N, N> displayedImpedance() const { return derived().theoreticalImpedance(); }

  const Diagnostics& last() const noexcept { return d_; }
  const Gains& gains() const noexcept { return gains_; }
  const Model& model() const noexcept { return model_; }

 private:
  // tick(): the checks in order, with the kinematics supplied by the three callables.
  template <class InRange, class Forward, class Jacobian>
  Fault tickFrom(const JointVector& q, const TaskVector& x_proxy, ActuatorVector& tau_a, InRange&& inRange,
                 Forward&& forward, Jacobian&& jacobian) noexcept {
    tau_a.setZero();
    d_.clamped = false;
    d_.free_space = false;
    d_.unclamped.setZero();
    if (!q.allFinite() || !x_proxy.allFinite()) return fail(Fault::kNonFiniteInput);
    // A reading outside the mechanism's working range (a glitch, a miscalibrated sensor) is no
    // configuration at all: the model's forward() there is only a continuation, so render nothing.
    if (!inRange()) return fail(Fault::kOutOfRange);
    forward(d_.probe);
    if (!d_.probe.allFinite()) return fail(Fault::kNonFiniteResult);
    const TaskVector dx = x_proxy - d_.probe;
    jacobian(d_.J);
    if (!d_.J.allFinite()) return fail(Fault::kSingular);
    if (dx.isZero(0.0)) {  // free space: nothing to render, skip every solve
      d_.free_space = true;
      d_.joint_deviation.setZero();
      d_.subspace_proxy = q;
      d_.fault = Fault::kNone;
      return Fault::kNone;
    }
    const Fault f = derived().computeCommand(q, dx, d_.unclamped);
    if (f != Fault::kNone) return fail(f);
    if (zeroIfNonFinite(d_.unclamped) != Fault::kNone) return fail(Fault::kNonFiniteResult);
    tau_a = d_.unclamped;
    d_.clamped = clampSymmetric(tau_a, gains_.force_limit) > 0;
    d_.fault = Fault::kNone;
    return Fault::kNone;
  }

 protected:
  // Shared guard for methods that invert J: rank lost (not merely ill-conditioned) is a fault.
  bool rankLost(const RegularizedSolveInfo& info) const noexcept {
    return !(info.sigma_max > 0.0) || info.sigma_min < gains_.singular_threshold * info.sigma_max;
  }
  Fault fail(Fault f) noexcept {
    d_.fault = f;
    d_.unclamped.setZero();
    return f;
  }
  Derived& derived() noexcept { return static_cast<Derived&>(*this); }
  const Derived& derived() const noexcept { return static_cast<const Derived&>(*this); }

  const Model& model_;
  Gains gains_;
  Mat<N - A, N> Sn_;
  Diagnostics d_;
};

/// Standard proxy rendering projected onto the actuators (eq. 1); impedance eq. 2.
template <class Model>
class StandardRenderer : public UnderactuatedRendererBase<Model, StandardRenderer<Model>> {
  using Base = UnderactuatedRendererBase<Model, StandardRenderer<Model>>;
  friend Base;

 public:
  using Base::Base;
  static constexpr const char* kName = "standard";

 private:
  Fault computeCommand(const typename Base::JointVector&, const typename Base::TaskVector& dx,
                       typename Base::ActuatorVector& tau) noexcept {
    tau = underactuated::standardForce(this->d_.J, this->model_.selection(), this->gains_.Zx, dx);
    return Fault::kNone;
  }
  Mat<Base::N, Base::N> theoreticalImpedance() const {
    return underactuated::standardImpedance(this->d_.J, this->model_.selection(), this->gains_.Zx);
  }
};

/// Null-space force optimization (eq. 3-4): the task force is first projected off the directions
/// that load the non-actuated joints; impedance eq. 5.
template <class Model>
class NullSpaceRenderer : public UnderactuatedRendererBase<Model, NullSpaceRenderer<Model>> {
  using Base = UnderactuatedRendererBase<Model, NullSpaceRenderer<Model>>;
  friend Base;

 public:
  using Base::Base;
  static constexpr const char* kName = "null-space";

 private:
  Fault computeCommand(const typename Base::JointVector&, const typename Base::TaskVector& dx,
                       typename Base::ActuatorVector& tau) noexcept {
    projector_ = projector(&this->d_.solve);
    // J_n losing rank is harmless here: the damped projector removes nothing in the lost direction.
    tau = underactuated::nullSpaceForce(this->d_.J, this->model_.selection(), projector_, this->gains_.Zx, dx);
    return Fault::kNone;
  }
  Mat<Base::T, Base::T> projector(RegularizedSolveInfo* info) const {
    return underactuated::nullSpaceProjector<Base::T, Base::N, Base::A>(this->d_.J, this->Sn_,
                                                                         this->gains_.regularization, info);
  }
  Mat<Base::N, Base::N> theoreticalImpedance() const {
    return underactuated::nullSpaceImpedance(this->d_.J, this->model_.selection(), projector(nullptr),
                                             this->gains_.Zx);
  }
  Mat<Base::T, Base::T> projector_ = Mat<Base::T, Base::T>::Identity();
};

/// Linearized subspace proxy (eq. 7-8): the proxy deviation is mapped to a joint deviation by
/// least squares, and only its actuated part is rendered, through Z_q; impedance eq. 9.
template <class Model>
class LinearizedSubspaceRenderer : public UnderactuatedRendererBase<Model, LinearizedSubspaceRenderer<Model>> {
  using Base = UnderactuatedRendererBase<Model, LinearizedSubspaceRenderer<Model>>;
  friend Base;

 public:
  using Base::Base;
  static constexpr const char* kName = "subspace (linearized)";

 private:
  Fault computeCommand(const typename Base::JointVector& q, const typename Base::TaskVector& dx,
                       typename Base::ActuatorVector& tau) noexcept {
    auto& d = this->d_;
    d.joint_deviation = underactuated::linearizedSubspaceStep(d.J, dx, this->gains_.regularization, &d.solve);
    if (this->rankLost(d.solve)) return Fault::kSingular;
    d.subspace_proxy = q + d.joint_deviation;
    tau = underactuated::subspaceForce(this->model_.selection(), this->gains_.Zq, d.joint_deviation);
    return Fault::kNone;
  }
  Mat<Base::N, Base::N> theoreticalImpedance() const {
    return underactuated::linearizedSubspaceImpedance(this->d_.J, this->model_.selection(), this->gains_.Zq,
                                                      this->gains_.regularization);
  }
};

/// Nonlinear subspace proxy (eq. 6): q* solved iteratively, warm-started from the previous tick's
/// q* (from q on the first tick, after reset() or after a fault). Impedance eq. 9, exactly: with
/// the proxy held still q* does not depend on q.
template <class Model>
class NonlinearSubspaceRenderer : public UnderactuatedRendererBase<Model, NonlinearSubspaceRenderer<Model>> {
  using Base = UnderactuatedRendererBase<Model, NonlinearSubspaceRenderer<Model>>;
  friend Base;

 public:
  static constexpr const char* kName = "subspace (nonlinear)";
  NonlinearSubspaceRenderer(const Model& model, const typename Base::Gains& gains,
                            const SubspaceSolveOptions& solver = {})
      : Base(model, gains), solver_(solver) {
    if (!(solver.tolerance > 0.0) || solver.max_iterations < 1 || solver.max_iterations > 1000)
      throw Error("nonlinear subspace solver: tolerance must be > 0 and max_iterations in [1, 1000]");
    solver_.regularization = gains.regularization;
  }
  /// Forget the warm start (e.g. after the proxy jumped or the device was re-homed).
  void reset() noexcept { warm_ = false; }
  const SubspaceSolveOptions& solverOptions() const noexcept { return solver_; }

 private:
  Fault computeCommand(const typename Base::JointVector& q, const typename Base::TaskVector& dx,
                       typename Base::ActuatorVector& tau) noexcept {
    auto& d = this->d_;
    const typename Base::TaskVector x_proxy = d.probe + dx;
    if (!warm_) q_star_ = q;
    d.nonlinear = solveSubspaceProxy(this->model_, x_proxy, q_star_, solver_);
    // The warm start (last tick's q*) makes the usual tick one iteration. After a jump of the proxy
    // a local solve can stall where the joint-space domain of f is not convex (a linkage that
    // cannot assemble between start and solution). Then solve again from a better seed: the
    // model's closed-form inverse of the proxy where it has one, else the measured state.
    if (d.nonlinear.fault == Fault::kNotConverged) {
      bool reseeded = false;
      if constexpr (kHasInverseKinematics<Model>) reseeded = this->model_.inverse(x_proxy, q_star_);
      if (!reseeded && warm_) {
        q_star_ = q;
        reseeded = true;
      }
      if (reseeded) {
        const SubspaceSolveReport first = d.nonlinear;
        d.nonlinear = solveSubspaceProxy(this->model_, x_proxy, q_star_, solver_);
        d.nonlinear.iterations += first.iterations;
        d.nonlinear.evaluations += first.evaluations;
      }
    }
    // Any solver fault zeroes the command and drops the warm start.
    if (d.nonlinear.fault != Fault::kNone) {
      warm_ = false;
      return d.nonlinear.fault;
    }
    warm_ = true;
    d.subspace_proxy = q_star_;
    d.joint_deviation = q_star_ - q;
    tau = underactuated::subspaceForce(this->model_.selection(), this->gains_.Zq, d.joint_deviation);
    return Fault::kNone;
  }
  Mat<Base::N, Base::N> theoreticalImpedance() const {
    return underactuated::subspaceImpedance(this->model_.selection(), this->gains_.Zq);
  }

  SubspaceSolveOptions solver_;
  typename Base::JointVector q_star_ = Base::JointVector::Zero();
  bool warm_ = false;
};

}  // namespace uhaptics
