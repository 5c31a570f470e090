#pragma once
// Passivity at the scene's port: the observer and controller of the servo path's passivity layer
// (PassivePolicy, docs/passivity.md). It watches only the share of a device's command that renders
// the scene (the scene's force mapped to the joints), not the device's own fields (gravity
// compensation, null-space control, a position controller's regulator), and it measures that share
// against what a continuous-time scene would have done along the same path, so it sees the energy the
// sampling and the command delay generate, and nothing the scene stores.
//
// Each servo tick k, joints q_k measured at the start of the period, the policy's efforts e_k and
// their scene share s_k (efforts minus the policy's own fields):
//
//   dq       = q_k - q_{k-1}
//   p        = the port effort applied over the period just ended: s + the layer's change of the
//              command, as sent d = command_delay ticks before it (the board applies u_{k-1-d})
//   booked  += p . dq                              the scene port's work on the user
//   r        = (s_{k-1} + s_k) / 2 . dq            the continuous-time scene's work along the same
//                                                  path (trapezoidal): for a spring, the change of its
//                                                  stored energy to second order
//   stored  -= r; overdrawn = max(0, -stored); stored = max(stored, 0)
//                                                  a passive scene never gives back more than it has
//                                                  taken in since the contact began
//   excess  += (p . dq - r) + overdrawn            generated energy: what the sampling and the delay
//                                                  add, and what the scene itself gives beyond its store;
//                                                  a press stores nothing here, so a ring shows from its
//                                                  first cycle
//   excess   = max(excess, 0); excess = stored = 0 while s_k = 0 and no command with a scene
//                                                  share is in flight: absorbed energy is forgotten at
//                                                  once, everything at a release
//   n        = s_k / |s_k|, w = n . dq_db / T      the rate along the scene's effort, from the last
//                                                  period's displacement with a dead band of half a
//                                                  sensor step per joint (no estimator lag)
//   alpha    = min((excess - pending) / (T w^2), cap),  cap = m_n / (2 T (1 + d)), m_n = 1 / (n^T M^-1 n)
//   u_k      = clamp(e_k - alpha w n, limits)
//
// where pending is what the brakes already sent but not yet applied will dissipate at the current
// rate, and the cap is scaled by the brakes' record: while the brakes applied over the last ten or so
// periods have pushed with the motion more than against it (a displacement of one encoder count that
// turns back next period looks like motion and is not), the cap shrinks by 10 % a period, and it
// grows back while they dissipate. Within the limits the brake is shortened as a whole, so it stays
// along n. Why these choices:
// - Reference energy following (Ryu, Preusche, Hannaford and Hirzinger 2005) with the scene's
//   stored energy estimated from its own effort along the path, so no scene needs to state it: for
//   a sampled spring the increment is K |dq|^2 / 2 per period, the work Colgate and Brown's K T / 2
//   describes, and the layer adds that damping during contact motion and no more; an active scene
//   (an application's negative damper) overdraws its store and is damped like the sampling's energy.
// - The brake along the scene's share, not on every joint: J^T n has no null-space component, so the
//   redundant devices' self-motion is not braked and their null-space control stays off the balance.
// - The cap from the inertia m_n an effort along n meets (1 / (n^T M^-1 n): the rest of the
//   mechanism, the null space included, gives way to it; at the tool it is the effective mass along
//   the wall's normal): a damper on the last period's rate acting d periods later stays well damped
//   on that inertia below m_n / (2 T (1 + d)) (the joint harness's cap); actuator limits bound it
//   further.
// Limits: the reference is the scene's effort at the readings the policy got, so delay inside the
// scene (an application thread computing forces from older positions) is not seen; displacements
// below one sensor step carry no brake, so a ring inside one count is left to the device's friction
// (Abbott and Okamura 2005).
//
// Units: efforts N m (N), positions rad (m), inertia kg m^2 (kg), damping N m s/rad (N s/m),
// energy J. noexcept and allocation-free per tick (storage of fixed maximum size); the command is
// finite and within the limits.
#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

#include "uhaptics/core/fault.hpp"

namespace uhaptics {

inline constexpr int kScenePortMaxDim = 16;
/// Largest command delay the layer aligns its booking with [periods].
inline constexpr int kScenePortMaxDelay = 3;

struct ScenePortPassivityOptions {
  using Vector = Eigen::Matrix<double, Eigen::Dynamic, 1, Eigen::ColMajor, kScenePortMaxDim, 1>;
  using Matrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor, kScenePortMaxDim,
                               kScenePortMaxDim>;

  /// false: observe only; the efforts pass bit for bit.
  bool enabled = true;
  /// Periods between the reading a command is computed from and the period it acts in, 0..3.
  int command_delay = 0;
  /// Per joint: one sensor step [rad or m], >= 0 (0: ideal sensor). Empty: all ideal.
  Vector resolution;
  /// Joint-space inertia of the joints [kg m^2, kg on a prismatic joint], symmetric positive
  /// definite, dim x dim: sizes the damping cap. Empty: no inertia known, no damping unless
  /// max_damping is set.
  Matrix inertia;
  /// An explicit cap on the damping along the scene's effort [N m s/rad], finite and >= 0; NaN: the
  /// inertia's cap alone. With both, the smaller.
  double max_damping = std::numeric_limits<double>::quiet_NaN();
  /// Generated energy tolerated before damping [J], finite and >= 0.
  double energy_threshold = 0.0;
  /// Per joint effort limits, each > 0 (infinity: none). Empty: none. Enabled, the command is held
  /// to them and the work booked is the held command's.
  Vector effort_limit;
};

class ScenePortPassivity {
 public:
  using Options = ScenePortPassivityOptions;
  using Vector = Options::Vector;
  using Matrix = Options::Matrix;

  /// dim: joint count, 1..kScenePortMaxDim. Throws uhaptics::Error for a dim or option out of range.
  explicit ScenePortPassivity(const Options& options, Eigen::Index dim) : options_(options), dim_(dim) {
    const auto fail = [](const std::string& what) { throw Error("ScenePortPassivity: " + what); };
    if (dim < 1 || dim > kScenePortMaxDim) fail("dim = " + std::to_string(dim) + ", accepted 1..16");
    if (options.command_delay < 0 || options.command_delay > kScenePortMaxDelay)
      fail("command_delay = " + std::to_string(options.command_delay) + ", accepted 0..3");
    const auto sized = [dim](Eigen::Index n) { return n == 0 || n == dim; };
    if (!sized(options.resolution.size()) || !sized(options.effort_limit.size()))
      fail("resolution and effort_limit take 0 or dim entries");
    if (!(options.resolution.array() >= 0.0).all() || !options.resolution.allFinite())
      fail("resolution must be finite and >= 0");
    if (!(options.effort_limit.array() > 0.0).all()) fail("effort_limit must be > 0");
    if (options.inertia.size() != 0) {
      const Matrix& M = options.inertia;
      const char* what = "inertia must be a finite symmetric positive definite dim x dim matrix";
      if (M.rows() != dim || M.cols() != dim || !M.allFinite() || !M.isApprox(M.transpose())) fail(what);
      const Eigen::LLT<Matrix> llt(M);
      if (llt.info() != Eigen::Success) fail(what);
      mobility_ = llt.solve(Matrix::Identity(dim, dim));
    }
    if (!std::isnan(options.max_damping) && !(std::isfinite(options.max_damping) && options.max_damping >= 0.0))
      fail("max_damping must be finite and >= 0, or NaN");
    if (!(std::isfinite(options.energy_threshold) && options.energy_threshold >= 0.0))
      fail("energy_threshold must be finite and >= 0");
    dead_band_ = options.resolution.size() == 0 ? Vector::Zero(dim) : Vector(0.5 * options.resolution);
    last_q_ = last_scene_ = brake_ = dq_ = direction_ = rate_ = Vector::Zero(dim);
    for (auto& p : port_) p = Vector::Zero(dim);
    for (auto& b : brakes_) b = Vector::Zero(dim);
  }

  /// One servo tick: q the joints read at the start of this period, efforts the policy's, scene its
  /// scene share (efforts minus its own fields), period T [s]. Writes the command to u_out (which
  /// must not alias efforts or scene); the caller applies exactly u_out. Returns kNone, or the fault
  /// that left u_out at zero (kInvalidParameter: a size or period; kNonFiniteInput; kNonFiniteResult)
  /// and restarts the observation.
  template <typename DQ, typename DE, typename DS>
  Fault update(const Eigen::MatrixBase<DQ>& q, const Eigen::MatrixBase<DE>& efforts,
               const Eigen::MatrixBase<DS>& scene, double period, Vector& u_out) noexcept {
    damping_ = 0.0;
    if (q.size() != dim_ || efforts.size() != dim_ || scene.size() != dim_) return fail(Fault::kInvalidParameter, u_out);
    if (!q.allFinite() || !efforts.allFinite() || !scene.allFinite() || !std::isfinite(period))
      return fail(Fault::kNonFiniteInput, u_out);
    if (!(period > 0.0)) return fail(Fault::kInvalidParameter, u_out);
    const int d = options_.command_delay;

    // Close the period just ended with the port effort that acted over it.
    if (started_) dq_ = q - last_q_;
    else dq_.setZero();
    if (started_) {
      // The scene's store follows its own work whether or not this chain's command acted yet.
      const double reference = 0.5 * (last_scene_ + scene).dot(dq_);
      const bool booked = sent_ > d;
      const double work = booked ? port_[static_cast<std::size_t>(d)].dot(dq_) : 0.0;
      const double absorbed = booked ? -brakes_[static_cast<std::size_t>(d)].dot(dq_) : 0.0;
      const double stored = stored_ - reference;
      const double overdrawn = stored < 0.0 ? -stored : 0.0;
      const double generated = overdrawn + (booked ? work - reference : 0.0);
      if (!std::isfinite(generated) || !std::isfinite(absorbed)) return fail(Fault::kNonFiniteResult, u_out);
      stored_ = stored + overdrawn;
      // The brakes' record over the last periods: while they have pushed with the motion more than
      // against it, the cap shrinks; while they dissipate, it grows back.
      if (absorbed != 0.0) {
        record_ = kRecordDecay * record_ + absorbed;
        efficacy_ = record_ < 0.0 ? kEfficacyCut * efficacy_ : std::min(1.0, efficacy_ + kEfficacyRecovery);
      }
      booked_ += work;
      dissipated_ += absorbed;
      generated_ += generated;
      excess_ = std::max(0.0, excess_ + generated);
    }
    last_q_ = q;
    started_ = true;
    const double scene_norm = scene.norm();
    // Released (no scene effort, none still in flight): nothing of the contact stays on the balance.
    bool in_flight = false;
    for (int j = 0; j < d && j < sent_; ++j) in_flight = in_flight || !port_[static_cast<std::size_t>(j)].isZero(0.0);
    if (scene_norm == 0.0 && !in_flight) excess_ = stored_ = 0.0;
    peak_excess_ = std::max(peak_excess_, excess_);

    brake_.setZero();
    const double excess = excess_ - options_.energy_threshold;
    if (options_.enabled && excess > 0.0 && scene_norm > 0.0) {
      direction_ = scene / scene_norm;
      for (Eigen::Index i = 0; i < dim_; ++i) rate_(i) = std::abs(dq_(i)) > dead_band_(i) ? dq_(i) / period : 0.0;
      const double w = direction_.dot(rate_);
      double pending = 0.0;  // brakes sent and not yet applied, at this rate
      for (int j = 0; j < d; ++j) pending -= brakes_[static_cast<std::size_t>(j)].dot(rate_) * period;
      const double to_dissipate = excess - std::max(0.0, pending);
      const double capacity = period * w * w;  // energy one unit of damping takes out over a period
      const double cap = efficacy_ * capAlong(direction_, period);
      if (to_dissipate > 0.0 && capacity > 0.0 && cap > 0.0) {
        damping_ = to_dissipate > cap * capacity ? cap : to_dissipate / capacity;
        brake_ = (-damping_ * w) * direction_;
        ++active_ticks_;
      }
    }

    u_out = efforts;  // observing only: bit for bit
    if (options_.enabled) {
      if (options_.effort_limit.size() != 0) {
        // The limits shorten the brake as a whole: clipped joint by joint it would turn away from
        // the scene's direction, and a damper turned off the rate it acts against can push.
        const Vector& limit = options_.effort_limit;
        u_out = u_out.cwiseMax(-limit).cwiseMin(limit);
        double share = 1.0;
        for (Eigen::Index i = 0; i < dim_; ++i) {
          const double room = brake_(i) > 0.0 ? limit(i) - u_out(i) : limit(i) + u_out(i);
          if (brake_(i) != 0.0 && room < share * std::abs(brake_(i))) share = std::max(0.0, room / std::abs(brake_(i)));
        }
        brake_ *= share;
        u_out = (u_out + brake_).cwiseMax(-limit).cwiseMin(limit);
      } else {
        u_out += brake_;
      }
    }
    if (!u_out.allFinite()) return fail(Fault::kNonFiniteResult, u_out);
    for (int j = kScenePortMaxDelay; j > 0; --j) {
      port_[static_cast<std::size_t>(j)] = port_[static_cast<std::size_t>(j - 1)];
      brakes_[static_cast<std::size_t>(j)] = brakes_[static_cast<std::size_t>(j - 1)];
    }
    port_[0] = scene + (u_out - efforts);  // what was applied, less the policy's own fields
    brakes_[0] = brake_;
    last_scene_ = scene;
    if (sent_ <= kScenePortMaxDelay) ++sent_;
    return Fault::kNone;
  }

  /// The damping cap along a unit joint-space direction at this period [N m s/rad].
  double capAlong(const Vector& unit, double period) const noexcept {
    double cap = std::numeric_limits<double>::infinity();
    if (mobility_.size() != 0)
      cap = 1.0 / (unit.dot(mobility_ * unit) * 2.0 * period * (1.0 + options_.command_delay));
    else if (std::isnan(options_.max_damping))
      cap = 0.0;
    if (!std::isnan(options_.max_damping)) cap = std::min(cap, options_.max_damping);
    return std::isfinite(cap) && cap > 0.0 ? cap : 0.0;
  }

  /// A period whose command the layer did not produce: the next update() starts a new chain; the
  /// totals and counters are kept, the excess is forgotten.
  void interrupt() noexcept {
    started_ = false;
    sent_ = 0;
    excess_ = stored_ = 0.0;
    damping_ = 0.0;
    brake_.setZero();
    record_ = 0.0;
    efficacy_ = 1.0;
  }
  /// A new session: totals and counters too.
  void reset() noexcept {
    interrupt();
    booked_ = generated_ = dissipated_ = 0.0;
    peak_excess_ = 0.0;
    active_ticks_ = faults_ = 0;
  }

  /// Net work the scene's port (its share plus the layer's damping, as applied) did on the user [J].
  double bookedWork() const noexcept { return booked_; }
  /// Energy the port generated against the continuous-time scene (and any the scene gave beyond its
  /// store), summed over the session [J].
  double generated() const noexcept { return generated_; }
  /// The generated energy waiting to be dissipated, and its largest value [J].
  double excess() const noexcept { return excess_; }
  double peakExcess() const noexcept { return peak_excess_; }
  /// Work the applied damping took from the user [J].
  double dissipated() const noexcept { return dissipated_; }
  std::uint64_t activeTicks() const noexcept { return active_ticks_; }
  std::uint64_t faults() const noexcept { return faults_; }
  /// Damping along the scene's effort added on the last tick [N m s/rad] (0: none).
  double lastDamping() const noexcept { return damping_; }

 private:
  Fault fail(Fault fault, Vector& u_out) noexcept {
    u_out = Vector::Zero(dim_);
    interrupt();
    ++faults_;
    return fault;
  }

  Options options_;
  Eigen::Index dim_;
  Vector dead_band_, last_q_, last_scene_, brake_, dq_, direction_, rate_;
  // The record's memory is about 10 braking periods; per period of an active record the cap is cut
  // by 10 %, per period of a dissipating one it regains a tenth of the full cap. A deeper cut also
  // throttles the brakes a real ring needs near its turning points (the RHI's delayed wall).
  static constexpr double kRecordDecay = 0.9;
  static constexpr double kEfficacyCut = 0.9;
  static constexpr double kEfficacyRecovery = 0.1;
  double record_ = 0.0;    // the brakes' recent work taken from the user [J]
  double efficacy_ = 1.0;  // share of the cap the brake's record allows, (0, 1]
  Matrix mobility_;  // the inertia's inverse (empty without one)
  std::array<Vector, kScenePortMaxDelay + 1> port_, brakes_;  // sent commands' port share and brake, newest first
  int sent_ = 0;  // commands sent in this chain (up to kScenePortMaxDelay + 1)
  bool started_ = false;
  double stored_ = 0.0;  // the scene's stored energy since the contact began, from its own work [J]
  double booked_ = 0.0, generated_ = 0.0, excess_ = 0.0, peak_excess_ = 0.0, dissipated_ = 0.0, damping_ = 0.0;
  std::uint64_t active_ticks_ = 0, faults_ = 0;
};

}  // namespace uhaptics
