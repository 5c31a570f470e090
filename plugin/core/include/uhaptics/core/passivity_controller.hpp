#pragma once
// Time-domain passivity controller in joint space (Hannaford & Ryu, "Time-domain passivity control
// of haptic interfaces", IEEE T-RA 18(1), 2002), impedance type: the renderer computes joint
// efforts u from the measured joints, and this controller adds a variable damping whenever the
// device has given out more energy than it has taken in.
//
// Each servo tick n, with the joints q_n measured at the start of the period:
//
//   E_out(n) = sum_{k<n} u_out,k . (q_{k+1} - q_k)     (the observer, as PassivityObserver: exact
//                                                      work of the command actually applied under
//                                                      a zero-order hold, damping included)
//   excess   = E_out(n) - energy_threshold
//   alpha    = excess / (T |qd_n|^2)                   (when excess > 0; else 0)
//   alpha_i  = min(alpha, max_damping_i)               (per joint)
//   u_out,n  = u_n - diag(alpha_i) qd_n
//
// so that, if the joints keep their rate over the next period, the added damping dissipates exactly
// the excess: alpha |qd|^2 T = excess. What it really dissipates is whatever the next sample shows;
// the observer counts the applied command, so any shortfall stays on E_out and the controller acts
// on it again one tick later. Like every time-domain passivity controller it reacts one period
// after the energy appears, and it cannot see energy the renderer stores (a compressed virtual
// spring keeps E_out negative until the spring has given back more than it has taken in). With
// quantized positions the observer has the encoder's resolution: a joint chattering within one
// count c of a sampled spring K reads K c^2 / 2 generated per count flip whatever the true work
// is, so a quantized wall needs Coulomb friction above K c / 2 (Abbott and Okamura, 2005) to come
// to rest, with or without this controller.
//
// Choices:
// - One alpha for every joint (Ryu and Hannaford's scalar damping): the added effort -alpha qd
//   opposes the joint velocity vector, so it removes energy without steering the motion, and the
//   excess is planned out in one period whatever the direction of motion. Per-joint caps clip it
//   joint by joint; a capped joint removes less and the rest stays on E_out for later ticks (the
//   other joints are not asked to make up for it, which would turn the damping toward whichever
//   joint happens to be uncapped).
// - Velocity guard: a joint whose rate magnitude is below min_rate gets no damping and does not
//   count in |qd|^2. Set min_rate to the rate the device's estimator resolves (about one encoder
//   count over its longest window): below it the sign of the estimate is not to be trusted, and
//   damping against a wrong-signed rate injects energy instead of removing it. With every joint
//   under the guard nothing is added and the excess waits on E_out.
// - Cap without division by ~0: alpha_i = max_damping_i whenever excess > max_damping_i T |qd|^2,
//   so the quotient is only formed when it is at most the cap.
// - Effort limits (optional): a device holds each command to its actuators' limits, and work the
//   observer counts must be the work of what the device applies. With limits set, the renderer's
//   effort is held first, then the damped command; the damping the limit cut off is neither
//   applied nor counted as dissipated, and the energy it would have taken stays on E_out.
//
// Joint units: efforts in N m (N for a prismatic joint), positions in rad (m), damping in
// N m s/rad (N s/m), energy in J. noexcept and allocation-free per tick (N = Eigen::Dynamic uses
// storage of fixed maximum size kPassivityControllerMaxDynamicDim); never produces a non-finite command.
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

#include "uhaptics/core/fault.hpp"

namespace uhaptics {

/// Largest joint count of PassivityController<Eigen::Dynamic>.
inline constexpr int kPassivityControllerMaxDynamicDim = 16;

template <int N>
struct PassivityControllerOptions {
  static constexpr int kMaxDim = N == Eigen::Dynamic ? kPassivityControllerMaxDynamicDim : N;

  /// false: the command passes through unchanged; the energy is still observed.
  bool enabled = true;
  /// Cap on the damping added to each joint [N m s/rad], finite and >= 0. Take it from the
  /// device's spec (the largest joint damping its servo renders stably). 0 (the default): observe
  /// only, never damp.
  double max_damping = 0.0;
  /// Per-joint caps [N m s/rad], each finite and >= 0; when non-empty (size = joint count) they
  /// replace max_damping.
  Eigen::Matrix<double, Eigen::Dynamic, 1, Eigen::ColMajor, kMaxDim, 1> max_damping_per_joint;
  /// Velocity guard [rad/s], finite and >= 0: joints slower than this get no damping (see the
  /// header comment). A joint reading exactly 0 never gets damping, whatever this is.
  double min_rate = 1e-3;
  /// Net generated energy tolerated before damping is added [J], finite and >= 0; only the energy
  /// above it is dissipated.
  double energy_threshold = 0.0;
  /// Per-joint effort limits [N m], each > 0 (infinity: none); when non-empty (size = joint count)
  /// the enabled controller holds every command to +-limit and observes the held command.
  /// Disabled, it passes the command through unchanged, limits included.
  Eigen::Matrix<double, Eigen::Dynamic, 1, Eigen::ColMajor, kMaxDim, 1> effort_limit;
};

template <int N>
class PassivityController {
 public:
  static_assert(N == Eigen::Dynamic || N > 0, "PassivityController: N > 0 or Eigen::Dynamic");
  using Options = PassivityControllerOptions<N>;
  static constexpr int kMaxDim = Options::kMaxDim;
  using Vector = Eigen::Matrix<double, N, 1, Eigen::ColMajor, kMaxDim, 1>;

  /// dim: joint count (must be N when N is fixed; 1..kMaxDim for Eigen::Dynamic).
  /// Throws uhaptics::Error when dim or an option is out of range.
  explicit PassivityController(const Options& options, Eigen::Index dim = N > 0 ? N : 0)
      : options_(options), dim_(dim) {
    if (dim < 1 || dim > kMaxDim || (N > 0 && dim != N))
      throw Error("PassivityController: dim = " + std::to_string(dim) + ", accepted 1.." +
                  std::to_string(kMaxDim) + (N > 0 ? " and equal to N" : ""));
    const auto nonNegative = [](double x) { return std::isfinite(x) && x >= 0.0; };
    if (!nonNegative(options.max_damping))
      throw Error("PassivityController: max_damping must be finite and >= 0 [N m s/rad]");
    if (!nonNegative(options.min_rate))
      throw Error("PassivityController: min_rate must be finite and >= 0 [rad/s]");
    if (!nonNegative(options.energy_threshold))
      throw Error("PassivityController: energy_threshold must be finite and >= 0 [J]");
    const auto& per_joint = options.max_damping_per_joint;
    if (per_joint.size() != 0 && per_joint.size() != dim)
      throw Error("PassivityController: max_damping_per_joint has " + std::to_string(per_joint.size()) +
                  " entries, accepted 0 or " + std::to_string(dim));
    cap_ = Vector::Constant(dim, options.max_damping);
    for (Eigen::Index i = 0; i < per_joint.size(); ++i) {
      if (!nonNegative(per_joint(i)))
        throw Error("PassivityController: max_damping_per_joint(" + std::to_string(i) +
                    ") must be finite and >= 0 [N m s/rad]");
      cap_(i) = per_joint(i);
    }
    const auto& limit = options.effort_limit;
    if (limit.size() != 0 && limit.size() != dim)
      throw Error("PassivityController: effort_limit has " + std::to_string(limit.size()) + " entries, accepted 0 or " +
                  std::to_string(dim));
    for (Eigen::Index i = 0; i < limit.size(); ++i)
      if (!(limit(i) > 0.0))
        throw Error("PassivityController: effort_limit(" + std::to_string(i) + ") must be > 0 [N m]");
    limited_ = limit.size() != 0;
    last_q_ = Vector::Zero(dim);
    last_u_ = Vector::Zero(dim);
    brake_ = Vector::Zero(dim);
    alpha_ = Vector::Zero(dim);
  }

  /// One servo tick. q: joints measured at the start of this period; qd: their rates (the rate
  /// estimator's output); u: the renderer's efforts for this period; period: T [s], > 0.
  /// Writes the efforts to apply to u_out (may be the same object as u); the caller must apply
  /// exactly u_out over the period, since the next tick counts its work.
  /// Returns Fault::kNone, or the fault that left u_out at zero: kNonFiniteInput (NaN or Inf in q,
  /// qd, u or period), kInvalidParameter (period <= 0, or a size other than dim()),
  /// kNonFiniteResult (work or command overflowed). A non-finite q or an overflowed work leaves the
  /// period ending at that sample uncounted; observation restarts at the next valid q.
  template <typename DQ, typename DR, typename DU>
  Fault update(const Eigen::MatrixBase<DQ>& q, const Eigen::MatrixBase<DR>& qd, const Eigen::MatrixBase<DU>& u,
               double period, Vector& u_out) noexcept {
    alpha_.setZero();
    if (q.size() != dim_ || qd.size() != dim_ || u.size() != dim_) return fail(Fault::kInvalidParameter, false, u_out);
    if (!q.allFinite()) return fail(Fault::kNonFiniteInput, false, u_out);

    // Close the last period with the work of the command actually applied over it.
    if (started_) {
      const double energy = energy_out_ + last_u_.dot(q - last_q_);
      const double dissipated = dissipated_ + brake_.dot(q - last_q_);
      if (!std::isfinite(energy) || !std::isfinite(dissipated)) return fail(Fault::kNonFiniteResult, false, u_out);
      energy_out_ = energy;
      dissipated_ = dissipated;
      peak_ = std::max(peak_, energy_out_);
    }
    last_q_ = q;
    started_ = true;

    if (!qd.allFinite() || !u.allFinite() || !std::isfinite(period)) return fail(Fault::kNonFiniteInput, true, u_out);
    if (!(period > 0.0)) return fail(Fault::kInvalidParameter, true, u_out);

    brake_.setZero();
    const double excess = energy_out_ - options_.energy_threshold;
    if (options_.enabled && excess > 0.0) {
      double rate2 = 0.0;  // |qd|^2 over the joints above the guard
      for (Eigen::Index i = 0; i < dim_; ++i)
        if (qd(i) != 0.0 && std::abs(qd(i)) >= options_.min_rate) rate2 += qd(i) * qd(i);
      const double capacity = period * rate2;  // energy one unit of damping dissipates [rad^2/s]
      if (capacity > 0.0) {
        bool any = false;
        for (Eigen::Index i = 0; i < dim_; ++i) {
          if (qd(i) == 0.0 || std::abs(qd(i)) < options_.min_rate) continue;
          alpha_(i) = excess > cap_(i) * capacity ? cap_(i) : excess / capacity;
          brake_(i) = alpha_(i) * qd(i);
          any = any || alpha_(i) > 0.0;
        }
        if (any) ++active_ticks_;
      }
    }

    if (!options_.enabled) {
      u_out = u;  // bit for bit
    } else if (!limited_) {
      u_out = u - brake_;
    } else {
      // What the device applies: the renderer's effort held to the limit, then the damped command
      // held again; brake_ keeps only the damping that survived, which is what dissipates.
      u_out.resize(dim_);
      for (Eigen::Index i = 0; i < dim_; ++i) {
        const double limit = options_.effort_limit(i);
        const double held = std::clamp(static_cast<double>(u(i)), -limit, limit);
        u_out(i) = std::clamp(held - brake_(i), -limit, limit);
        brake_(i) = held - u_out(i);
      }
    }
    if (!u_out.allFinite()) return fail(Fault::kNonFiniteResult, true, u_out);
    last_u_ = u_out;
    last_fault_ = Fault::kNone;
    return Fault::kNone;
  }

  /// Forgets the energy, counters and last command; the next update starts a new observation.
  void reset() noexcept {
    energy_out_ = dissipated_ = 0.0;
    peak_ = -std::numeric_limits<double>::infinity();
    active_ticks_ = faults_ = 0;
    last_fault_ = Fault::kNone;
    started_ = false;
    last_u_.setZero();
    brake_.setZero();
    alpha_.setZero();
  }

  /// A period whose command this controller did not produce (no reading, or efforts another stage
  /// chose): the next update() starts a new observation chain without counting the work across
  /// the gap. Energy, peak and counters are kept.
  void interrupt() noexcept {
    started_ = false;
    last_u_.setZero();
    brake_.setZero();
    alpha_.setZero();
  }

  /// Switches the damping on or off; observation goes on either way.
  void setEnabled(bool enabled) noexcept { options_.enabled = enabled; }
  bool enabled() const noexcept { return options_.enabled; }
  const Options& options() const noexcept { return options_; }
  Eigen::Index dim() const noexcept { return dim_; }

  /// Net work done by the applied commands on the user so far [J] (positive: the device gave energy).
  double energyOut() const noexcept { return energy_out_; }
  /// Largest value energyOut() reached [J] (0 before the first closed period).
  double peakEnergyOut() const noexcept { return peak_ > -std::numeric_limits<double>::infinity() ? peak_ : 0.0; }
  /// Work the added damping has absorbed so far, sum alpha qd . (q_{k+1} - q_k) [J].
  double dissipated() const noexcept { return dissipated_; }
  /// Ticks on which some joint got damping > 0.
  std::uint64_t activeTicks() const noexcept { return active_ticks_; }
  /// Ticks that returned a fault (and a zero command).
  std::uint64_t faults() const noexcept { return faults_; }
  /// The last tick's fault (Fault::kNone when it produced a command).
  Fault lastFault() const noexcept { return last_fault_; }
  /// Per-joint damping added on the last tick [N m s/rad] (zeros when none).
  const Vector& lastDamping() const noexcept { return alpha_; }

 private:
  // Zero command for this period. keep_chain: q was valid and recorded, so the zero command's
  // (zero) work over the coming period is observed; otherwise observation restarts.
  Fault fail(Fault fault, bool keep_chain, Vector& u_out) noexcept {
    u_out = Vector::Zero(dim_);
    last_u_.setZero();
    brake_.setZero();
    alpha_.setZero();
    started_ = keep_chain;
    ++faults_;
    last_fault_ = fault;
    return fault;
  }

  Options options_;
  Eigen::Index dim_;
  Vector cap_, last_q_, last_u_, brake_, alpha_;  // brake_: alpha qd, the effort removed from u
  double energy_out_ = 0.0;
  double dissipated_ = 0.0;
  double peak_ = -std::numeric_limits<double>::infinity();
  std::uint64_t active_ticks_ = 0;
  std::uint64_t faults_ = 0;
  Fault last_fault_ = Fault::kNone;
  bool started_ = false;
  bool limited_ = false;  // options_.effort_limit is set
};

}  // namespace uhaptics
