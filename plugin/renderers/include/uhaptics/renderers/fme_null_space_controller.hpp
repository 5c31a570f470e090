#pragma once
// Force-manipulability null-space controller for redundant haptic devices (paper 003):
//
//   tau   = J^T (alpha F) + (I - J^T J#^T) tau_S,      J# = M^-1 J^T (J M^-1 J^T)^-1
//   tau_S = -beta d nu/dq - K_d q_dot - k_L d P/dq
//
// The primary task is the force F a renderer (a virtual wall, a CHAI3D force algorithm) asks for;
// alpha <= 1 scales it uniformly when an actuator would saturate, so its direction is kept. The
// secondary task moves the device along its self-motion manifold so that its torque-limit-weighted
// force manipulability ellipsoid matches a desired one: in free motion and soft contact the minor
// axis lies along the motion (light, low back-drive friction), in stiff contact the major axis
// lies along the force (strong). The saturation observer V of the primary torques drives a
// hysteresis switch between the two with a half-cosine blend (ellipsoid_transition.hpp). P is a
// smooth barrier of the device's joint limits (joint_limits.hpp): zero away from them, so the
// paper's controller is unchanged there, and growing without bound at them, so the self-motion
// never drives the arm into a stop (the paper's device has them; the paper does not model them).
// Optionally (a device's safety envelope, not the paper's) the null-space torque is bounded in norm
// and rises smoothly after reset() instead of starting at whatever the gradient asks for.
//
// Generic over any model satisfying the kinematic-model interface with kJoints > kTask; uses the
// model's Jacobian derivatives, mass matrix and joint limits when it has them (model_capabilities.hpp). The
// tick never throws and never allocates; on bad input it reports a Fault and commands zero torque
// (non-finite input) or the primary task alone (singular Jacobian, undefined cost), always within
// the torque limits.
#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>

#include "uhaptics/core/ellipsoid_transition.hpp"
#include "uhaptics/core/fault.hpp"
#include "uhaptics/core/fme_cost.hpp"
#include "uhaptics/core/joint_limits.hpp"
#include "uhaptics/core/limits.hpp"
#include "uhaptics/core/null_space.hpp"
#include "uhaptics/core/saturation_observer.hpp"
#include "uhaptics/models/planar_linkage_model.hpp"

namespace uhaptics {

/// Which desired ellipsoid the secondary task tracks.
enum class FmeEllipsoidMode {
  kAuto,   // observer-driven switching (the paper's actuator saturation controller)
  kFree,   // always the free-motion ellipsoid (the paper's case A, eps = 0)
  kStiff,  // always the stiff-contact ellipsoid (case B, eps = 1)
};

template <int kTask>
struct FmeControllerOptions {
  double mu = 5.0;        // axis scaling: K = mu lambda_max(M_hat_home), zeta = lambda_min(M_hat_home) / mu
  double beta = 20.0;     // gradient gain [N m per unit of d nu/dq]
  double damping = 0.1;   // K_d [N m s/rad]
  double observer_shape = 50.0;  // S of eq. 14 (the paper's Fig. 6 value)
  EllipsoidTransitionOptions transition;  // eps1 = 0.7, eps2 = 0.95, rho = 0.003, smooth
  FmeEllipsoidMode mode = FmeEllipsoidMode::kAuto;
  Vec<kTask> motion_direction = Vec<kTask>::Unit(kTask - 1);  // free-motion minor axis (the palpation axis u)
  double major_axis = 0.0;  // K override (> 0); 0 = from mu and the home configuration
  double minor_axis = 0.0;  // zeta override (> 0); 0 = from mu and the home configuration
  bool dynamically_consistent = true;  // false: kinematic (Moore-Penrose) null space
  fme::GradientMethod gradient = fme::GradientMethod::kAnalytic;
  double contact_force_threshold = 1e-6;  // |F| below this counts as free motion [N]
  double min_inverse_condition = 1e-6;    // lambda_min / lambda_max of J W W J^T below this = singular
  // The stiff ellipsoid's major axis follows the contact force's direction through a first-order
  // filter with this time constant while any of the stiff ellipsoid is in use (it takes the force's
  // direction directly while the free one is settled, so a switch starts from the current force).
  // The filter keeps a proxy force's tick-to-tick turns (a CHAI3D proxy's tangential part resetting)
  // out of the null-space torque, which the stiff ellipsoid's elongated axes would amplify
  // (docs/rhi.md, "In CHAI3D"). 0: each tick's force (the paper).
  double stiff_direction_time = 0.0;  // [s], >= 0
  // Joint-limit avoidance (limits from the model's jointLimits() or setJointLimits()): barrier
  // active within limit_margin of a bound, torque limit_gain (1 - margin^2 / d^2) at distance d.
  // limit_gain = 0 turns it off. Assumed values, the paper has no limit term (docs/rhi.md,
  // "Joint limits").
  double limit_gain = 0.5;    // k_L [N m], >= 0
  double limit_margin = 0.25; // delta [rad], > 0
  // Approach-speed cap (a velocity damper): a limited coordinate s_j = C_j q may approach a bound
  // at most at limit_speed, falling in proportion to the distance inside the margin (zero at the
  // bound); faster approach is braked by (m_j / limit_brake_time) times the excess, projected into
  // the null space like the barrier, with m_j = 1 / (C_j M^-1 P C_j^T) the inertia the coordinate
  // shows to a null-space torque along C_j (P = I - J^T J#^T; M^-1 P is the null-space mobility),
  // so one tick removes dt / limit_brake_time of the excess (0.2 at 1 kHz, 5 ms) whatever the
  // configuration. Where the coordinate can hardly move in the null space, m_j is capped at
  // 100 / (C_j M^-1 C_j^T) (mobility at least 1 % of the unconstrained one): a stop the null space
  // cannot reach is not braked with unbounded torque. The barrier is a potential and cannot
  // dissipate; the brake takes out the self-motion speed (e.g. after a free-to-stiff switch) that
  // would carry the arm into a stop, whose reaction is not in the null space and pushes the end
  // effector (docs/rhi.md, "Joint limits": why the brake, and why it is not sized by the
  // joint-space inertia C_j M C_j^T). Assumed values; limit_speed = 0 turns it off.
  double limit_speed = 2.0;        // [rad/s], >= 0
  double limit_brake_time = 0.005;  // [s], > 0 (5 servo periods at 1 kHz: stable in discrete time for T > dt / 2)
  // Null-space torque envelope: tau_N = r(t) min(1, max_null_space_torque / |tau_N,cmd|) tau_N,cmd
  // (Euclidean norm, one scale for the whole vector: its direction is kept, so the FME and
  // joint-limit terms keep their balance), before the actuator-limit fit. r rises as a half cosine,
  // r = (1 - cos(pi s)) / 2 with s = (t - t_0) / null_space_ramp_time, from 0 at the first tick after
  // reset() or after a tick that dropped the null-space torque (a fault) to 1: |tau_N| <= r
  // max_null_space_torque always, and per tick r grows by at most pi dt / (2 null_space_ramp_time).
  // The primary task J^T (alpha F) is not affected. Why: away from the configuration its desired
  // ellipsoid matches (e.g. the RHI at home, beta = 20) the FME gradient alone can ask for more
  // than the actuators' limits, so an unbounded controller drives them to their limits with no
  // contact at all (docs/rhi.md, "In CHAI3D"). Defaults: unbounded and no ramp (0), the paper's
  // controller; the CHAI3D device sets its own (CPlanarLinkageDevice.hpp).
  double max_null_space_torque = std::numeric_limits<double>::infinity();  // [N m], > 0
  double null_space_ramp_time = 0.0;                                       // [s], >= 0 (0: no ramp)
  // Energy tank of the null-space torque (Ferraguti, Secchi et al.; Franken et al.'s two-layer
  // approach): the tank E starts full at null_space_tank_capacity after reset(), pays the work the
  // applied null-space torque did on the device over each period, tau_N(k-1)^T (q(k) - q(k-1))
  // (its own damping's negative work refills it), gains null_space_tank_refill dt, and never holds
  // more than its capacity. Below a quarter of the capacity the null-space torque is scaled by
  // E / (capacity / 4), so the torque fades smoothly as the tank empties instead of stepping. Over
  // any interval of length T the self-motion control gives the device (and the hand holding it) at
  // most capacity + refill T net, whatever the desired ellipsoid does; the null-space torque keeps
  // its direction. The primary task is not affected. Defaults: no tank (the paper's controller).
  double null_space_tank_capacity = std::numeric_limits<double>::infinity();  // [J], > 0 (inf: no tank)
  double null_space_tank_refill = 0.0;                                         // [W], >= 0
};

/// What one tick computed (for logging and figures).
template <int kJoints, int kTask>
struct FmeControllerStatus {
  Fault fault = Fault::kNone;
  double observer = 1.0;   // V
  double omega = 1.0;      // activation (1 = free ellipsoid, 0 = stiff)
  double omega_target = 1.0;  // where omega is going (1 free, 0 stiff); equal to omega when settled
  double cost = 0.0;       // nu
  double alpha = 1.0;      // force scaling
  double null_space_scale = 1.0;  // fraction of the FME null-space torque kept to stay within the torque limits
  double null_space_ramp = 1.0;   // start-up ramp r in [0, 1] (Options::null_space_ramp_time)
  double null_space_bound_scale = 1.0;  // min(1, max_null_space_torque / |tau_null_command|)
  double null_space_tank = std::numeric_limits<double>::infinity();  // tank energy E [J] (inf: no tank)
  double null_space_tank_scale = 1.0;   // the tank's scale of the null-space torque, in [0, 1]
  bool skipped_contact_work = false;  // free-motion fast path taken
  Vec<kTask> force = Vec<kTask>::Zero();  // force actually commanded (alpha F)
  Vec<kJoints> tau_primary = Vec<kJoints>::Zero();
  Vec<kJoints> tau_null = Vec<kJoints>::Zero();          // applied null-space torque (after ramp, bound, limits)
  Vec<kJoints> tau_null_command = Vec<kJoints>::Zero();  // (I - J^T J#^T) tau_S before ramp, bound, limits
  Vec<kJoints> tau_limit_command = Vec<kJoints>::Zero();  // its joint-limit avoidance part
};

template <class Model>
class FmeNullSpaceController {
  static_assert(kIsKinematicModel<Model>, "the FME controller needs a kinematic model");
  static_assert(Model::kJoints > Model::kTask, "the FME controller needs a redundant device");

 public:
  static constexpr int N = Model::kJoints;
  static constexpr int M = Model::kTask;
  using JointVector = Vec<N>;
  using TaskVector = Vec<M>;
  using TaskMatrix = Mat<M, M>;
  using Options = FmeControllerOptions<M>;
  using Status = FmeControllerStatus<N, M>;

  /// torque_limits T_i > 0; home: the configuration whose FME sets K and zeta. Joint limits come
  /// from the model when it has them (none otherwise; see setJointLimits). Throws
  /// uhaptics::Error on invalid limits, a singular home configuration or invalid options.
  FmeNullSpaceController(const Model& model, const JointVector& torque_limits, const JointVector& home,
                         const Options& options = {});

  /// Validates and applies options (allowed between ticks, e.g. from a GUI). On invalid options
  /// returns Fault::kInvalidParameter and keeps the previous ones.
  Fault setOptions(const Options& o) noexcept {
    const bool ok = std::isfinite(o.mu) && o.mu > 0.0 && std::isfinite(o.beta) && o.beta >= 0.0 &&
                    std::isfinite(o.damping) && o.damping >= 0.0 && std::isfinite(o.observer_shape) &&
                    o.observer_shape > 0.0 && o.transition.valid() && o.motion_direction.allFinite() &&
                    o.motion_direction.norm() > 0.0 && std::isfinite(o.major_axis) && o.major_axis >= 0.0 &&
                    std::isfinite(o.minor_axis) && o.minor_axis >= 0.0 && o.contact_force_threshold >= 0.0 &&
                    o.min_inverse_condition > 0.0 && o.min_inverse_condition < 1.0 && std::isfinite(o.limit_gain) &&
                    o.limit_gain >= 0.0 && std::isfinite(o.limit_margin) && o.limit_margin > 0.0 &&
                    std::isfinite(o.limit_speed) && o.limit_speed >= 0.0 && std::isfinite(o.limit_brake_time) &&
                    o.limit_brake_time > 0.0 && o.max_null_space_torque > 0.0 &&
                    std::isfinite(o.null_space_ramp_time) && o.null_space_ramp_time >= 0.0 &&
                    std::isfinite(o.stiff_direction_time) && o.stiff_direction_time >= 0.0 &&
                    o.null_space_tank_capacity > 0.0 && std::isfinite(o.null_space_tank_refill) &&
                    o.null_space_tank_refill >= 0.0;
    if (!ok) return Fault::kInvalidParameter;
    const fme::EllipsoidScales s = fme::ellipsoidScales(home_fme_, o.mu);
    const double major = o.major_axis > 0.0 ? o.major_axis : s.major;
    const double minor = o.minor_axis > 0.0 ? o.minor_axis : s.minor;
    TaskMatrix free_fme;
    if (!(major >= minor) || !fme::axisAlignedEllipsoid(o.motion_direction, minor, major, free_fme))
      return Fault::kInvalidParameter;
    options_ = o;
    major_ = major;
    minor_ = minor;
    free_fme_ = free_fme;
    fme::axisAlignedEllipsoid(stiff_direction_, major_, minor_, stiff_fme_);  // direction is never zero
    return Fault::kNone;
  }

  /// Replaces the free-motion desired ellipsoid by an arbitrary one (e.g. from a task planner).
  /// Rejects (Fault::kInvalidParameter, old one kept) anything not symmetric positive definite.
  Fault setFreeEllipsoid(const TaskMatrix& free_fme) noexcept {
    if (!fme::isSymmetricPositiveDefinite(free_fme)) return Fault::kInvalidParameter;
    free_fme_ = free_fme;
    return Fault::kNone;
  }

  /// Replaces the joint limits the null-space task keeps away from (e.g. tighter software stops).
  /// Rejects invalid ones (Fault::kInvalidParameter, old ones kept); JointLimits<N>{} = none.
  Fault setJointLimits(const JointLimits<N>& limits) noexcept {
    if (!limits.valid()) return Fault::kInvalidParameter;
    joint_limits_ = limits;
    has_joint_limits_ = limits.any();
    return Fault::kNone;
  }

  /// Back to the free-motion ellipsoid (the stiff one in FmeEllipsoidMode::kStiff) with nothing in
  /// progress; the null-space torque ramps up again from the next tick (Options::null_space_ramp_time).
  void reset() noexcept {
    transition_.reset(options_.mode == FmeEllipsoidMode::kStiff ? 0.0 : 1.0);
    stiff_direction_ = options_.motion_direction.normalized();
    fme::axisAlignedEllipsoid(stiff_direction_, major_, minor_, stiff_fme_);
    direction_time_ = kNever;
    status_ = Status{};
    status_.omega = status_.omega_target = transition_.omega();
    ramp_start_ = kNever;
    status_.null_space_tank = options_.null_space_tank_capacity;
    tank_time_ = kNever;
  }

  /// One servo tick at time t [s]: joint state q [rad] and q_dot [rad/s], requested end-effector
  /// force F [N] in the model's task frame. Writes tau [N m] (always finite, |tau_i| <= T_i) and
  /// returns the fault (also in status()): kNonFiniteInput or kNonFiniteResult (tau = 0),
  /// kSingular or kInvalidParameter (primary task only).
  Fault tick(double t, const JointVector& q, const JointVector& qd, const TaskVector& F, JointVector& tau) noexcept;

  const Status& status() const noexcept { return status_; }
  const Options& options() const noexcept { return options_; }
  const TaskMatrix& desiredEllipsoid() const noexcept { return desired_; }
  const TaskMatrix& freeEllipsoid() const noexcept { return free_fme_; }
  const TaskMatrix& stiffEllipsoid() const noexcept { return stiff_fme_; }
  /// K and zeta in use.
  double majorAxis() const noexcept { return major_; }
  double minorAxis() const noexcept { return minor_; }
  const TaskMatrix& homeFme() const noexcept { return home_fme_; }
  const JointVector& torqueLimits() const noexcept { return limits_; }
  const JointVector& inverseSquaredLimits() const noexcept { return inv_limits_sq_; }
  const JointLimits<N>& jointLimits() const noexcept { return joint_limits_; }

 private:
  // stiff_direction_ (a unit vector) towards the direction of F (|F| > 0), see Options::stiff_direction_time.
  void followContactDirection(double t, const TaskVector& F) noexcept {
    TaskVector u = F / F.norm();
    const double dt = t - direction_time_;
    direction_time_ = t;
    if (!(options_.stiff_direction_time > 0.0) || transition_.settledFree() || !(dt > 0.0)) {
      stiff_direction_ = u;
      return;
    }
    if (u.dot(stiff_direction_) < 0.0) u = -u;  // the ellipsoid of -u is the same: turn the short way
    const double k = 1.0 - std::exp(-dt / options_.stiff_direction_time);
    const TaskVector d = stiff_direction_ + k * (u - stiff_direction_);  // |d| >= 1/sqrt(2): at most 90 deg apart
    stiff_direction_ = d / d.norm();
  }

  // The start-up ramp r(t) (Options::null_space_ramp_time); the first call after reset() or a
  // dropped null space starts it (r = 0 there).
  double rampAt(double t) noexcept {
    if (ramp_start_ == kNever) ramp_start_ = t;
    if (!(options_.null_space_ramp_time > 0.0)) return 1.0;
    const double s = (t - ramp_start_) / options_.null_space_ramp_time;
    if (!(s < 1.0)) return 1.0;
    return 0.5 * (1.0 - std::cos(M_PI * std::max(s, 0.0)));
  }

  // Pays the work the null-space torque applied last period did on the way to q, adds the refill,
  // and returns the tank's scale for this period (Options::null_space_tank_capacity).
  double bookTank(double t, const JointVector& q) noexcept {
    const double capacity = options_.null_space_tank_capacity;
    if (!std::isfinite(capacity)) {
      status_.null_space_tank = capacity;
      return 1.0;
    }
    double energy = std::min(status_.null_space_tank, capacity);  // the capacity may have shrunk
    if (tank_time_ != kNever) {
      energy -= status_.tau_null.dot(q - tank_q_);
      energy += options_.null_space_tank_refill * std::max(0.0, t - tank_time_);
    }
    status_.null_space_tank = std::min(energy, capacity);
    tank_q_ = q;
    tank_time_ = t;
    return std::clamp(status_.null_space_tank / (kTankLowShare * capacity), 0.0, 1.0);
  }

  // Largest gamma in [0, 1] with |base_i + gamma add_i| <= T_i wherever add moves base outwards
  // (base itself is within the limits).
  double fitIntoLimits(const JointVector& base, const JointVector& add) const noexcept {
    double gamma = 1.0;
    for (int i = 0; i < N; ++i) {
      const double total = base(i) + add(i);
      if (std::abs(total) > limits_(i) && add(i) != 0.0) {
        const double room = (total > 0.0 ? limits_(i) : -limits_(i)) - base(i);
        gamma = std::min(gamma, std::max(0.0, room / add(i)));
      }
    }
    return gamma;
  }

  // Adds to tau the velocity damper of every bound within the margin (see Options::limit_speed).
  void addLimitBrake(const JointVector& q, const JointVector& qd, JointVector& tau) noexcept {
    const double margin = options_.limit_margin;
    mobility_.noalias() = mass_inv_ * projector_;  // joint accelerations per unit of null-space torque
    for (int j = 0; j < N; ++j) {
      const auto row = joint_limits_.map.row(j);
      const double s = row.dot(q), sd = row.dot(qd);
      // Distance and approach speed to each bound; +1: the distance grows with s (lower bound).
      for (const auto& [distance, approach, sign] :
           {std::tuple<double, double, double>{s - joint_limits_.lower(j), -sd, 1.0},
            std::tuple<double, double, double>{joint_limits_.upper(j) - s, sd, -1.0}}) {
        if (!std::isfinite(distance)) continue;
        const double excess = approach - options_.limit_speed * std::clamp(distance / margin, 0.0, 1.0);
        if (excess <= 0.0) continue;
        const double free_mobility = row * mass_inv_ * row.transpose();
        const double null_mobility = row * mobility_ * row.transpose();
        const double inertia = 1.0 / std::max(null_mobility, kMinNullMobility * free_mobility);
        tau += (sign * inertia * excess / options_.limit_brake_time) * row.transpose();
      }
    }
  }

  void updateDesired(double t) noexcept {
    double omega = 1.0;
    switch (options_.mode) {
      case FmeEllipsoidMode::kFree: omega = 1.0; break;
      case FmeEllipsoidMode::kStiff: omega = 0.0; break;
      case FmeEllipsoidMode::kAuto:
        omega = transition_.update(t, status_.observer, (free_fme_ - stiff_fme_).norm(), options_.transition);
        break;
    }
    if (options_.mode != FmeEllipsoidMode::kAuto) transition_.reset(omega);
    desired_ = omega * free_fme_ + (1.0 - omega) * stiff_fme_;
  }

  // Last line of defence: finite and within limits whatever happened above.
  Fault finish(Fault fault, JointVector& tau, bool keep_primary) noexcept {
    if (!keep_primary) {
      tau.setZero();
      status_.tau_primary.setZero();
      status_.force.setZero();
    }
    if (fault != Fault::kNone) {
      status_.tau_null.setZero();
      status_.tau_null_command.setZero();
      status_.tau_limit_command.setZero();
      status_.null_space_ramp = 0.0;
      ramp_start_ = kNever;  // the null space dropped out: it ramps up again, never steps back in
    }
    status_.omega = transition_.omega();
    status_.omega_target = transition_.target();
    if (zeroIfNonFinite(tau) != Fault::kNone && fault == Fault::kNone) fault = Fault::kNonFiniteResult;
    clampSymmetric(tau, limits_);
    status_.fault = fault;
    return fault;
  }

  Model model_;
  JointVector limits_, inv_limits_sq_;
  JointLimits<N> joint_limits_;
  bool has_joint_limits_ = false;
  TaskMatrix home_fme_ = TaskMatrix::Identity();
  Options options_;
  double major_ = 1.0, minor_ = 1.0;
  TaskMatrix free_fme_ = TaskMatrix::Identity(), stiff_fme_ = TaskMatrix::Identity(),
             desired_ = TaskMatrix::Identity();
  TaskVector stiff_direction_ = TaskVector::Unit(M - 1);
  EllipsoidTransition transition_;
  Status status_;
  static constexpr double kNever = -std::numeric_limits<double>::infinity();  // a time not yet set
  double ramp_start_ = kNever;  // time of the ramp's first tick
  double direction_time_ = kNever;  // time of the last contact-direction update
  double tank_time_ = kNever;       // time of the tank's last booking
  JointVector tank_q_ = JointVector::Zero();  // the joints at that booking
  static constexpr double kTankLowShare = 0.25;  // the null-space torque fades below this share of the tank
  // Workspace (preallocated: the tick touches no heap).
  Mat<M, N> J_;
  JointVector grad_ = JointVector::Zero(), limit_grad_ = JointVector::Zero();
  Mat<N, N> mass_ = Mat<N, N>::Identity(), mass_inv_, projector_, mobility_;
  static constexpr double kMinNullMobility = 0.01;  // limit brake: share of the unconstrained mobility
};

template <class Model>
FmeNullSpaceController<Model>::FmeNullSpaceController(const Model& model, const JointVector& torque_limits,
                                                      const JointVector& home, const Options& options)
    : model_(model), limits_(torque_limits) {
  if (!limits_.allFinite() || !(limits_.minCoeff() > 0.0))
    throw Error("FME controller: torque limits must be finite and positive");
  if constexpr (kHasJointLimits<Model>) {
    if (setJointLimits(model_.jointLimits()) != Fault::kNone) throw Error("FME controller: invalid joint limits");
  }
  inv_limits_sq_ = fme::inverseSquaredLimits(limits_);
  Mat<M, N> J;
  model_.jacobian(home, J);
  if (!home.allFinite() || !fme::weightedFme(J, inv_limits_sq_, home_fme_, 1e-9))
    throw Error("FME controller: the home configuration is singular (no force manipulability ellipsoid)");
  if (setOptions(options) != Fault::kNone)
    throw Error("FME controller: invalid options (gains must be finite and >= 0, mu > 0, thresholds in "
                "[0, 1] with eps1 <= eps2, a non-zero motion direction, max_null_space_torque > 0, "
                "null_space_ramp_time and stiff_direction_time finite and >= 0, null_space_tank_capacity > 0, "
                "null_space_tank_refill finite and >= 0)");
  reset();
}

template <class Model>
Fault FmeNullSpaceController<Model>::tick(double t, const JointVector& q, const JointVector& qd, const TaskVector& F,
                                          JointVector& tau) noexcept {
  tau.setZero();
  status_.skipped_contact_work = false;
  if (!std::isfinite(t) || !q.allFinite() || !qd.allFinite() || !F.allFinite())
    return finish(Fault::kNonFiniteInput, tau, false);
  // The tank books last period's work first: a tick that drops the null space still paid for it.
  status_.null_space_tank_scale = bookTank(t, q);
  model_.jacobian(q, J_);
  if (!J_.allFinite()) return finish(Fault::kNonFiniteResult, tau, false);

  // Primary task, scaled into the torque box keeping the force direction.
  const bool contact = F.norm() > options_.contact_force_threshold;
  if (!contact && options_.mode != FmeEllipsoidMode::kStiff && transition_.settledFree()) {
    // Free motion, nothing near saturation: no observer, scaling, stiff ellipsoid or blend.
    status_.skipped_contact_work = true;
    status_.observer = 1.0;
    status_.alpha = 1.0;
    status_.force.setZero();
    status_.tau_primary.setZero();
    desired_ = free_fme_;
  } else {
    status_.tau_primary.noalias() = J_.transpose() * F;
    status_.observer = saturationObserver(status_.tau_primary, limits_, options_.observer_shape);
    status_.alpha = scaleIntoBox(status_.tau_primary, limits_);
    status_.force = status_.alpha * F;
    // The stiff ellipsoid's major axis follows the contact force, except while the blend back to
    // the free one runs: that starts when the force has fallen (V >= eps2), and as it vanishes
    // (a proxy leaving a surface) its direction is undefined and can turn through 180 deg within
    // a few ticks, which would sweep the desired ellipsoid round and step the null-space torque
    // (docs/rhi.md, "In CHAI3D").
    const bool leaving_stiff = transition_.target() == 1.0 && transition_.inProgress();
    if (contact && !leaving_stiff) {
      followContactDirection(t, F);
      fme::axisAlignedEllipsoid(stiff_direction_, major_, minor_, stiff_fme_);
    }
    updateDesired(t);
  }
  tau = status_.tau_primary;

  // Secondary task in the null space. Failure here leaves the primary task alone.
  if (!fme::fmeCostGradient(model_, q, J_, inv_limits_sq_, desired_, options_.gradient, status_.cost, grad_,
                            options_.min_inverse_condition)) {
    TaskMatrix unused;  // failure path only: tell a singular arm from an undefined cost
    const bool singular = !fme::weightedFme(J_, inv_limits_sq_, unused, options_.min_inverse_condition);
    return finish(singular ? Fault::kSingular : Fault::kInvalidParameter, tau, true);
  }
  // The mass matrix: for the dynamically consistent inverse and the limit brake (identity, in
  // kg m^2, for a model without one).
  if constexpr (kHasMassMatrix<Model>) {
    model_.massMatrix(q, mass_);
  } else {
    mass_.setIdentity();
  }
  Eigen::LLT<Mat<N, N>> llt(mass_);
  const bool mass_valid = llt.info() == Eigen::Success;
  if (mass_valid) {
    mass_inv_ = llt.solve(Mat<N, N>::Identity());
  } else if (options_.dynamically_consistent) {
    return finish(Fault::kInvalidParameter, tau, true);
  } else {
    mass_inv_.setIdentity();  // kinematic projector: the mass matrix only sizes the limit brake
  }
  const bool projected = options_.dynamically_consistent
                             ? nullSpaceProjector(J_, mass_inv_, projector_)
                             : nullSpaceProjector(J_, Mat<N, N>(Mat<N, N>::Identity()), projector_);
  if (!projected) return finish(Fault::kSingular, tau, true);
  const JointVector tau_s = -options_.beta * grad_ - options_.damping * qd;
  status_.tau_null_command.noalias() = projector_ * tau_s;
  status_.tau_limit_command.setZero();
  if (has_joint_limits_ && options_.limit_gain > 0.0) {
    jointLimitGradient(joint_limits_, q, options_.limit_margin, limit_grad_);
    limit_grad_ *= -options_.limit_gain;
    if (options_.limit_speed > 0.0) addLimitBrake(q, qd, limit_grad_);
    status_.tau_limit_command.noalias() = projector_ * limit_grad_;
    status_.tau_null_command += status_.tau_limit_command;
  }
  // The envelope (ramp and norm bound), then keep the primary task intact: shrink tau_N until
  // every joint is within its limit. Each is one scale of the whole vector: the FME and
  // joint-limit terms shrink together, so where they balance (the settled configuration near a
  // limit) they still do.
  status_.null_space_ramp = rampAt(t);
  const double command_norm = status_.tau_null_command.norm();
  status_.null_space_bound_scale =
      command_norm > options_.max_null_space_torque ? options_.max_null_space_torque / command_norm : 1.0;
  status_.tau_null = (status_.null_space_ramp * status_.null_space_bound_scale * status_.null_space_tank_scale) *
                     status_.tau_null_command;
  const double gamma = fitIntoLimits(tau, status_.tau_null);
  status_.tau_null *= gamma;
  tau += status_.tau_null;
  status_.null_space_scale = gamma;
  return finish(Fault::kNone, tau, true);
}

// The shipped planar linkages' controllers are compiled once, in fme_null_space_controller.cpp: the
// constructor and the tick, defined out of the class for that reason, are the controller's heavy
// part (its fixed-size decompositions), and every renderer, scene, tool and test uses them.
extern template class FmeNullSpaceController<PlanarLinkageModel<3>>;
extern template class FmeNullSpaceController<PlanarLinkageModel<4>>;

}  // namespace uhaptics
