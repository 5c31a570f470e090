#include "uhaptics/experiments/zwidth.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <utility>

#include "uhaptics/backends/joint_io.hpp"
#include "uhaptics/core/fault.hpp"
#include "uhaptics/core/passivity_controller.hpp"
#include "uhaptics/experiments/parallel.hpp"
#include "zwidth_common.hpp"

namespace uhaptics::experiments {

namespace {

using zwidth_detail::Channels;
using zwidth_detail::HardwarePath;
using zwidth_detail::PeakToPeak;

using zwidth_detail::kPi;
using zwidth_detail::raisedCosine;
using zwidth_detail::searchStiffness;
using zwidth_detail::setBracket;
using zwidth_detail::ticksFor;
// Identification: the sinusoidal torque's frequency, its smooth onset, how many whole cycles are
// measured, and how many sensor steps the motion must span to be measured through quantization.
constexpr double kIdPeriod = 1e-3;
constexpr double kIdFrequencyHz = 20.0;
constexpr double kIdMinFrequencyHz = 5.0;
constexpr double kIdOnsetS = 0.3;
constexpr int kIdCycles = 10;
constexpr double kIdMinSteps = 20.0;
constexpr double kIdFirstAmplitude = 0.1;  // of the effort limit
constexpr double kIdMaxAmplitude = 0.3;
// The identification's motion must span this many sensor steps for the b it returns to hold the
// bound to 10 %: the work per cycle is read through the steps, an error of about one step in the
// amplitude.
constexpr double kBoundMinSteps = 10.0;
// A wall run has run away when the joint is this many press depths past the wall.
constexpr double kRunawayDepths = 50.0;
// ... and diverges when it oscillates wider than this many press depths.
constexpr double kDivergentDepths = 10.0;

// The 1-DoF plant of the closed-form check.
class MassDamperPlant final : public BoardPlant {
 public:
  explicit MassDamperPlant(const MassDamperParams& p) noexcept : p_(p) {}
  int jointCount() const noexcept override { return 1; }
  int actuatorCount() const noexcept override { return 1; }
  void readJoints(double* positions) noexcept override { positions[0] = q_; }
  void applyCommand(const double* efforts) noexcept override {
    u_ = std::isfinite(efforts[0]) ? std::clamp(efforts[0], -p_.effort_limit, p_.effort_limit) : 0.0;
  }
  void advance(double dt) noexcept override {
    if (!(dt > 0.0) || !std::isfinite(dt)) return;
    const int n = std::max(1, static_cast<int>(std::ceil(dt / kMaxStep)));
    const double h = dt / n;
    for (int i = 0; i < n; ++i) rk4(h);
  }
  bool readUserPoint(Vec3& position, Vec3& velocity) noexcept override {
    position = Vec3(q_, 0.0, 0.0);
    velocity = Vec3(v_, 0.0, 0.0);
    return true;
  }

 private:
  static constexpr double kMaxStep = 1e-5;
  double accel(double q, double v) const noexcept { return (u_ - p_.damping * v - p_.centring * q) / p_.inertia; }
  void rk4(double h) noexcept {
    const double q1 = v_, v1 = accel(q_, v_);
    const double q2 = v_ + 0.5 * h * v1, v2 = accel(q_ + 0.5 * h * q1, v_ + 0.5 * h * v1);
    const double q3 = v_ + 0.5 * h * v2, v3 = accel(q_ + 0.5 * h * q2, v_ + 0.5 * h * v2);
    const double q4 = v_ + h * v3, v4 = accel(q_ + h * q3, v_ + h * v3);
    q_ += h / 6.0 * (q1 + 2.0 * q2 + 2.0 * q3 + q4);
    v_ += h / 6.0 * (v1 + 2.0 * v2 + 2.0 * v3 + v4);
  }
  MassDamperParams p_;
  double q_ = 0.0, v_ = 0.0, u_ = 0.0;
};

// One plant driven as the hardware path drives it: sensed joints quantized to the spec's resolution,
// rates from the board's estimator over a sample clock of the servo period, the device's free-space
// control plus the wall on the joint, commanded `delay` periods after the reading; the user's torque
// on the joint acts at once (it is a hand, not a command).
class ServoHarness {
 public:
  ServoHarness(const ZWidthDevice& device, double period, int delay, FreeSpaceControl* free_space)
      : device_(device),
        plant_(device.make_plant ? device.make_plant(period) : nullptr),
        path_(device.spec, period, delay),
        free_space_(free_space) {
    if (!plant_) throw Error("Z-width: device '" + device.name + "' has no plant");
    if (plant_->jointCount() != device.spec.descriptor.joints ||
        plant_->actuatorCount() != device.spec.descriptor.actuators)
      throw Error("Z-width: device '" + device.name + "': the plant's joint or actuator count differs from its spec");
    if (free_space_) free_space_->reset(delay);
  }

  // Reads the plant; false when a reading is not finite.
  bool sense() noexcept { return path_.read(*plant_); }

  // One period: free-space efforts plus `wall` on the joint (delayed, within the effort limits),
  // plus the user's effort. False when the plant reports a fault.
  bool step(double wall, double user) noexcept {
    const long tick = path_.tick();
    Channels command{};
    if (free_space_ && !free_space_->efforts(path_.q().data(), path_.rates().data(), tick == 0, path_.period(),
                                             command.data()))
      command.fill(0.0);
    const int j = device_.joint;
    const double limit = device_.spec.descriptor.effort_limit[j];
    command[j] += wall;
    const auto slot = [](long t) { return static_cast<std::size_t>(t % (kMaxZWidthDelay + 1)); };
    pending_wall_[slot(tick)] = std::clamp(wall, -limit, limit);
    applied_wall_ = tick >= path_.delay() ? pending_wall_[slot(tick - path_.delay())] : 0.0;
    Channels applied = path_.command(command);
    applied[j] += user;
    plant_->applyCommand(applied.data());
    plant_->advance(path_.period());
    return plant_->lastFault() == Fault::kNone;
  }

  const Channels& q() const noexcept { return path_.q(); }
  const Channels& rates() const noexcept { return path_.rates(); }
  // The wall's share of the command that acted over the last period.
  double appliedWall() const noexcept { return applied_wall_; }

 private:
  const ZWidthDevice& device_;
  std::unique_ptr<BoardPlant> plant_;
  HardwarePath path_;
  FreeSpaceControl* free_space_;
  std::array<double, kMaxZWidthDelay + 1> pending_wall_{};
  double applied_wall_ = 0.0;
};

void checkJoint(const ZWidthDevice& device) {
  const int actuators = device.spec.descriptor.actuators;
  if (device.joint < 0 || device.joint >= actuators)
    throw Error("Z-width: device '" + device.name + "': joint " + std::to_string(device.joint) +
                " is not an actuated joint (0.." + std::to_string(actuators - 1) + ")");
  if (!(device.spec.descriptor.effort_limit[device.joint] > 0.0))
    throw Error("Z-width: device '" + device.name + "': the wall joint has no effort limit");
}

// What a sinusoidal torque on the joint puts in over whole cycles in steady state.
struct Excitation {
  bool ok = true;
  double work = 0.0;    // sum tau dq [J]
  double rate2 = 0.0;   // sum dq^2 / T  ~ integral qd^2 [rad^2/s]
  double travel = 0.0;  // sum |dq|  ~ integral |qd| [rad]
  double in_phase = 0.0;   // Re(tau / q) = k - m w^2 [N m/rad]
  double amplitude = 0.0;
  std::vector<double> q;  // the joint, every tick
};

Excitation excite(const ZWidthDevice& device, FreeSpaceControl* free_space, double amplitude, double frequency_hz) {
  const double T = kIdPeriod;
  const int j = device.joint;
  ServoHarness harness(device, T, 0, free_space);
  const long onset = ticksFor(kIdOnsetS, T);
  const long n = onset + ticksFor(kIdCycles / frequency_hz, T);
  const double omega = 2.0 * kPi * frequency_hz;
  Excitation e;
  e.q.reserve(static_cast<std::size_t>(n + 1));
  std::vector<double> torque;
  torque.reserve(static_cast<std::size_t>(n + 1));
  double previous_q = 0.0, previous_tau = 0.0;
  for (long k = 0; k <= n; ++k) {
    if (!harness.sense()) {
      e.ok = false;
      return e;
    }
    const double q = harness.q()[j];
    e.q.push_back(q);
    if (k > onset) {
      const double dq = q - previous_q;
      e.work += previous_tau * dq;
      e.rate2 += dq * dq / T;
      e.travel += std::abs(dq);
    }
    if (k == n) break;
    const double t = static_cast<double>(k) * T;
    const double tau = amplitude * raisedCosine(t / kIdOnsetS) * std::sin(omega * t);
    torque.push_back(tau);
    if (!harness.step(0.0, tau)) {
      e.ok = false;
      return e;
    }
    previous_q = q;
    previous_tau = tau;
  }
  // The in-phase part of the response, tau / q~ = k - m w^2 + i b w.
  double mean = 0.0;
  for (long k = onset; k < n; ++k) mean += e.q[static_cast<std::size_t>(k)];
  mean /= static_cast<double>(n - onset);
  double cross = 0.0, square = 0.0, lo = e.q[static_cast<std::size_t>(onset)], hi = lo;
  for (long k = onset; k < n; ++k) {
    const double dev = e.q[static_cast<std::size_t>(k)] - mean;
    cross += torque[static_cast<std::size_t>(k)] * dev;
    square += dev * dev;
    lo = std::min(lo, e.q[static_cast<std::size_t>(k)]);
    hi = std::max(hi, e.q[static_cast<std::size_t>(k)]);
  }
  e.in_phase = square > 0.0 ? cross / square : 0.0;
  e.amplitude = 0.5 * (hi - lo);
  return e;
}

}  // namespace

const char* toString(WallOutcome outcome) noexcept {
  switch (outcome) {
    case WallOutcome::kPassive: return "passive";
    case WallOutcome::kActive: return "active";
    case WallOutcome::kLimitCycle: return "limit cycle";
    case WallOutcome::kDivergent: return "divergent";
  }
  return "?";
}

double passivityMaxDamping(const JointIdentification& id, double period, int delay) noexcept {
  if (!(id.inertia > 0.0) || !(period > 0.0)) return 0.0;
  return id.inertia / (2.0 * period * (1.0 + std::max(0, delay)));
}

bool plantResolvesPeriod(const ZWidthDevice& device, double period) {
  checkJoint(device);
  std::unique_ptr<BoardPlant> plant = device.make_plant(period);
  if (!plant) throw Error("Z-width: device '" + device.name + "' has no plant");
  Channels before{}, after{};
  Vec3 p0 = Vec3::Zero(), v0 = Vec3::Zero(), p1 = Vec3::Zero(), v1 = Vec3::Zero();
  plant->readJoints(before.data());
  const bool has_point = plant->readUserPoint(p0, v0);
  Channels push{};
  push[device.joint] = 0.2 * device.spec.descriptor.effort_limit[device.joint];
  plant->applyCommand(push.data());
  plant->advance(period);
  plant->readJoints(after.data());
  if (has_point) plant->readUserPoint(p1, v1);
  return before != after || (has_point && (p0 != p1 || v0 != v1));
}

JointIdentification identifyJoint(const ZWidthDevice& device, double frequency_hz) {
  checkJoint(device);
  if (!(frequency_hz >= 0.0) || !std::isfinite(frequency_hz)) throw Error("Z-width: the identification frequency must be >= 0");
  const int j = device.joint;
  const double step = device.spec.position_resolution[j];
  const double limit = device.spec.descriptor.effort_limit[j];
  std::unique_ptr<FreeSpaceControl> free_space = device.make_free_space ? device.make_free_space() : nullptr;
  JointIdentification id;

  double frequency = frequency_hz > 0.0 ? frequency_hz : kIdFrequencyHz;
  double amplitude = kIdFirstAmplitude * limit;
  Excitation first = excite(device, free_space.get(), amplitude, frequency);
  const Excitation still = excite(device, free_space.get(), 0.0, frequency);
  if (!first.ok || !still.ok) return id;
  // Position-driven: the torque changes nothing the sensors see, even the largest one (at a high
  // frequency the first torque may move an inertia by less than a sensor step).
  const auto moved = [&](const Excitation& e) {
    double difference = 0.0;
    for (std::size_t k = 0; k < e.q.size() && k < still.q.size(); ++k)
      difference = std::max(difference, std::abs(e.q[k] - still.q[k]));
    return difference > std::max(step, 1e-12);
  };
  if (!moved(first)) {
    amplitude = kIdMaxAmplitude * limit;
    first = excite(device, free_space.get(), amplitude, frequency);
    if (!first.ok || !moved(first)) return id;
  }

  // Quantized sensors: a larger torque (then, at the default frequency, a lower frequency) until the
  // motion spans enough steps.
  if (step > 0.0 && first.amplitude < kIdMinSteps * step) {
    amplitude = std::min(kIdMaxAmplitude * limit, amplitude * kIdMinSteps * step / std::max(first.amplitude, step));
    first = excite(device, free_space.get(), amplitude, frequency);
    if (frequency_hz == 0.0 && first.ok && first.amplitude < kIdMinSteps * step) {
      frequency = std::max(kIdMinFrequencyHz, frequency * std::sqrt(std::max(first.amplitude, step) / (kIdMinSteps * step)));
      first = excite(device, free_space.get(), amplitude, frequency);
    }
  }
  const Excitation second = excite(device, free_space.get(), 2.0 * amplitude, frequency);
  // Inertia from the in-phase response at two frequencies: (k - m w1^2) - (k - m w2^2) = m (w2^2 - w1^2).
  const double high = 2.0 * frequency;
  const Excitation faster = excite(device, free_space.get(), std::min(kIdMaxAmplitude * limit, 4.0 * amplitude), high);
  if (!first.ok || !second.ok || !faster.ok) return id;

  // W = b int qd^2 + f_c int |qd| at two amplitudes.
  const double det = first.rate2 * second.travel - second.rate2 * first.travel;
  double b = std::numeric_limits<double>::quiet_NaN(), fc = 0.0;
  if (std::abs(det) > 1e-9 * (std::abs(first.rate2 * second.travel) + std::abs(second.rate2 * first.travel))) {
    b = (first.work * second.travel - second.work * first.travel) / det;
    fc = (first.rate2 * second.work - second.rate2 * first.work) / det;
  }
  if (!(fc >= 0.0) || !(b >= 0.0)) {  // no Coulomb part resolved: all of it viscous
    fc = 0.0;
    b = (first.work + second.work) / (first.rate2 + second.rate2);
  }
  const double w1 = 2.0 * kPi * frequency, w2 = 2.0 * kPi * high;
  id.responds = true;
  id.damping = b;
  id.coulomb = fc;
  id.inertia = (second.in_phase - faster.in_phase) / (w2 * w2 - w1 * w1);
  id.frequency_hz = frequency;
  id.amplitude = second.amplitude;
  return id;
}

double contactFrequencyHz(const JointIdentification& id, double rate_hz) noexcept {
  // The contact mode at the spring's bound K = 2 b / T rings at sqrt(K / m).
  if (!(id.inertia > 0.0) || !(id.damping > 0.0)) return kIdFrequencyHz;
  const double f = std::sqrt(2.0 * id.damping * rate_hz / id.inertia) / (2.0 * kPi);
  return std::clamp(f, kIdMinFrequencyHz, rate_hz / 10.0);
}

WallRun runWall(const ZWidthDevice& device, const JointIdentification& id, const WallCase& wall, double stiffness,
                const WallScript& script, FreeSpaceControl* free_space) {
  checkJoint(device);
  if (!(wall.rate_hz > 0.0) || !std::isfinite(wall.rate_hz)) throw Error("Z-width: the servo rate must be > 0");
  if (wall.delay < 0 || wall.delay > kMaxZWidthDelay) throw Error("Z-width: the command delay must be in 0..3 periods");
  if (!(wall.damping >= 0.0) || !std::isfinite(wall.damping)) throw Error("Z-width: the wall damping must be >= 0");
  if (!(stiffness > 0.0) || !std::isfinite(stiffness)) throw Error("Z-width: the wall stiffness must be > 0");

  const double T = 1.0 / wall.rate_hz;
  const int j = device.joint;
  const double step = device.spec.position_resolution[j];
  const double limit = device.spec.descriptor.effort_limit[j];
  const double depth = std::max(script.press_depth, kIdMinSteps * step);
  const double press = std::min(stiffness * depth, script.press_limit_fraction * limit);
  const double gap = std::max(5.0 * step, 0.05 * depth);

  const double t_press = script.settle_s;
  const double t_hold = t_press + script.press_ramp_s;
  const double t_release = t_hold + script.hold_s;
  const double t_free = t_release + script.release_ramp_s;
  const long n = ticksFor(t_free + script.after_s, T);
  const long n_press = ticksFor(t_press, T);
  const long n_release = ticksFor(t_release, T);
  const long n_hold_window = n_release - ticksFor(script.final_window_s, T);
  const long n_window = n - ticksFor(script.final_window_s, T);
  // After the release the hand stays on the joint as a light damper, so the device comes to rest and
  // the energy balance closes (the work it absorbs is energy the device gave the user).
  const double hand_damping = script.hand_damping_per_s * std::max(0.0, id.inertia);
  const auto user = [&](double t, double rate) {
    if (t < t_press) return 0.0;
    if (t < t_hold) return press * raisedCosine((t - t_press) / script.press_ramp_s);
    if (t < t_release) return press;
    if (t < t_free) return press * (1.0 - raisedCosine((t - t_release) / script.release_ramp_s));
    return -hand_damping * rate;
  };

  PassivityControllerOptions<1> pc_options;
  pc_options.enabled = wall.passivity;
  pc_options.max_damping = passivityMaxDamping(id, T, wall.delay);
  // Below one sensor step over the estimator's longest window the rate's sign is not to be trusted.
  pc_options.min_rate = step > 0.0 ? step / (JointRateEstimator::kMaxWindow * T) : 1e-6;
  PassivityController<1> passivity(pc_options);

  ServoHarness harness(device, T, wall.delay, free_space);
  WallRun run;
  run.wall = wall;
  run.stiffness = stiffness;
  run.press_torque = press;
  bool diverged = false, inside = false;
  double q_wall = 0.0, previous_q = 0.0, previous_user = 0.0, previous_wall = 0.0, user_work = 0.0;
  double user_variation = 0.0;  // total variation of the user's torque [N m]
  PeakToPeak window, hold;
  Eigen::Matrix<double, 1, 1> qv, rv, uv;
  PassivityController<1>::Vector out;
  for (long k = 0; k <= n; ++k) {
    if (!harness.sense()) {
      diverged = true;
      break;
    }
    const double q = harness.q()[j];
    if (k > 0) {
      user_work += previous_user * (q - previous_q);
      run.wall_energy_out += previous_wall * (q - previous_q);
    }
    if (k == n_press) q_wall = q + gap;
    if (k >= n_hold_window && k < n_release) {
      hold.add(q);
    }
    if (k >= n_window) {
      window.add(q);
    }
    if (k == n) break;

    double effort = 0.0;
    if (k >= n_press) {
      const double p = q - q_wall;
      if (std::abs(p) > kRunawayDepths * depth) {
        diverged = true;
        break;
      }
      if (p > 0.0) {
        effort = std::min(0.0, -(stiffness * p + wall.damping * harness.rates()[j]));
        run.max_penetration = std::max(run.max_penetration, p);
        if (!inside && k >= n_hold_window && k < n_release) ++run.hold_entries;
        if (!inside && k >= n_window) ++run.final_entries;
      }
      inside = p > 0.0;
    }
    qv(0) = q;
    rv(0) = harness.rates()[j];
    uv(0) = effort;
    passivity.update(qv, rv, uv, T, out);  // observes either way; damps when enabled
    const double u_user = user(static_cast<double>(k) * T, harness.rates()[j]);
    user_variation += std::abs(u_user - previous_user);
    if (!harness.step(out(0), u_user)) {
      diverged = true;
      break;
    }
    previous_q = q;
    previous_user = u_user;
    previous_wall = harness.appliedWall();
  }
  run.generated_energy = -user_work;
  run.passivity_dissipated = passivity.dissipated();
  run.final_amplitude = window.width();
  run.hold_amplitude = hold.width();
  const double peak_energy = 0.5 * stiffness * run.max_penetration * run.max_penetration;
  // Quantized readings q + e, |e| <= step / 2: sum tau_k (e_k+1 - e_k) = -sum e_k+1 (tau_k+1 - tau_k) for
  // a torque that starts and ends at zero, at most step / 2 times the torque's total variation.
  run.tolerance = script.relative_tolerance * peak_energy + 0.5 * step * (user_variation + std::abs(previous_user));
  const double wide = kDivergentDepths * depth;
  if (diverged || !std::isfinite(run.generated_energy) || run.hold_amplitude > wide || run.final_amplitude > wide)
    run.outcome = WallOutcome::kDivergent;
  // Bouncing, not one count flickering across the wall's surface.
  else if ((run.hold_entries >= 2 && run.hold_amplitude > 2.0 * step) ||
           (run.final_entries >= 2 && run.final_amplitude > 2.0 * step))
    run.outcome = WallOutcome::kLimitCycle;
  else if (run.generated_energy > run.tolerance)
    run.outcome = WallOutcome::kActive;
  else
    run.outcome = WallOutcome::kPassive;
  return run;
}

Boundary analyticBounds(const ZWidthDevice& device, const JointIdentification& id, const WallCase& wall) {
  checkJoint(device);
  Boundary b;
  b.wall = wall;
  const double lag = (1.0 + 2.0 * wall.delay) / wall.rate_hz;  // T/2 + d T, doubled
  const double damper = std::abs(wall.damping);
  b.k_colgate = std::max(0.0, 2.0 * (id.damping - damper) / lag);
  if (std::isfinite(device.param_viscous)) b.k_colgate_params = std::max(0.0, 2.0 * (device.param_viscous - damper) / lag);
  const double step = device.spec.position_resolution[device.joint];
  if (step > 0.0) b.k_quantization = 2.0 * id.coulomb / step;
  b.k_bound = std::min(b.k_colgate, b.k_quantization);
  b.limiting = b.k_quantization < b.k_colgate ? "Abbott-Okamura" : "Colgate-Brown";
  return b;
}

Boundary findBoundary(const ZWidthDevice& device, const JointIdentification& id, const WallCase& wall,
                      double start_k, const ZWidthOptions& options, FreeSpaceControl* free_space) {
  Boundary out = analyticBounds(device, id, wall);
  out.identification = id;
  const auto passive = [&](double k) {
    out.runs.push_back(runWall(device, id, wall, k, options.script, free_space));
    return out.runs.back().outcome == WallOutcome::kPassive;
  };
  const double k0 = start_k > 0.0 && std::isfinite(start_k) ? start_k : 1.0;
  setBracket(out, searchStiffness(passive, k0, options.max_bracket_steps, options.relative_precision));
  return out;
}

std::vector<WallCase> zwidthCases(const ZWidthOptions& options, double b) {
  std::vector<WallCase> cases;
  for (const double rate : options.rates_hz) {
    if (options.without_passivity) {
      for (const int d : options.delays) cases.push_back({rate, d, 0.0, false});
      for (const double fraction : options.damping_fractions)
        if (fraction > 0.0 && b > 0.0) cases.push_back({rate, 0, fraction * b, false});
    }
    if (options.with_passivity)
      for (const int d : options.delays) cases.push_back({rate, d, 0.0, true});
  }
  return cases;
}

bool boundResolved(const DeviceZWidth& result, const Boundary& boundary) noexcept {
  return !(result.resolution > 0.0) || boundary.identification.amplitude >= kBoundMinSteps * result.resolution;
}

bool colgateBrownApplies(const ZWidthDevice& device, const JointIdentification& id, const WallScript& script,
                         std::string* why) {
  const auto no = [why](const char* reason) {
    if (why) *why = reason;
    return false;
  };
  if (!id.responds) return no("the joint does not follow its effort (a position-driven user moves it)");
  if (!(id.inertia > 0.0)) return no("the joint's response is not mass-like (a stiffness dominates it)");
  if (!(id.damping > 0.0)) return no("the joint meets no positive viscous damping");
  // Energy per cycle of a sinusoid of amplitude A at w: viscous b pi w A^2, Coulomb 4 f_c A.
  const double w = 2.0 * kPi * id.frequency_hz;
  const double coulomb = 4.0 * id.coulomb * id.amplitude;
  const double viscous = id.damping * kPi * w * id.amplitude * id.amplitude;
  if (coulomb > 0.1 * (coulomb + viscous))
    return no("Coulomb friction takes over 10 % of the joint's dissipation, which the viscous bound leaves out");
  // A wall too soft for the press to reach it (the press torque is K times the press depth): what
  // the device does with the user alone.
  std::unique_ptr<FreeSpaceControl> free_space = device.make_free_space ? device.make_free_space() : nullptr;
  const WallRun alone = runWall(device, id, WallCase{1000.0, 0, 0.0, false}, 1e-3, script, free_space.get());
  if (alone.outcome != WallOutcome::kPassive)
    return no("the device's own control delivers energy to the user with no wall in reach: no passive K to bound");
  if (why) why->clear();
  return true;
}

ReproductionTable zwidthReproduction(const std::vector<DeviceZWidth>& results) {
  ReproductionTable table;
  char quantity[160];
  for (const DeviceZWidth& r : results) {
    if (!r.bound_applies) continue;
    for (const Boundary& b : r.boundaries) {
      if (b.wall.delay != 0 || b.wall.damping != 0.0 || b.wall.passivity || !(b.k_colgate > 0.0)) continue;
      if (!boundResolved(r, b)) continue;
      std::snprintf(quantity, sizeof quantity, "%s joint %d, %g kHz: spring wall's K_max / (2 b / T)", r.name.c_str(),
                    r.joint, b.wall.rate_hz / 1000.0);
      // NaN (nothing passive) or a lower bound (passive to the ceiling) misses the interval.
      const double ratio = b.above_range ? std::numeric_limits<double>::infinity() : b.k_max / b.k_colgate;
      table.add({kStabilityRows, quantity, 1.0, ratio, "within 10 % of Colgate-Brown", false, "", {},
                 Accepted::within(1.0, 0.10)});
    }
    const double off = boundaryStiffness(r, 1000.0, 0, false);
    const double on = boundaryStiffness(r, 1000.0, 0, true);
    if (std::isnan(off) && std::isnan(on)) continue;  // 1 kHz not swept
    std::snprintf(quantity, sizeof quantity, "%s joint %d, 1 kHz: passivity controller's K_max gain", r.name.c_str(),
                  r.joint);
    table.addBound(kStabilityRows, quantity, on / off, ">= 2", Accepted::atLeast(2.0), "x");
  }
  return table;
}

std::vector<DeviceZWidth> sweepZWidth(const std::vector<ZWidthDevice>& devices, const ZWidthOptions& options,
                                      const std::function<void()>& on_boundary) {
  if (options.rates_hz.empty()) throw Error("Z-width: no servo rate to sweep");
  for (const double r : options.rates_hz)
    if (!(r > 0.0) || !std::isfinite(r)) throw Error("Z-width: servo rates must be finite and > 0");
  if (options.delays.empty()) throw Error("Z-width: no command delay to sweep");
  for (const int d : options.delays)
    if (d < 0 || d > kMaxZWidthDelay) throw Error("Z-width: command delays must be in 0..3 periods");
  for (const double f : options.damping_fractions)
    if (!(f >= 0.0 && f < 1.0)) throw Error("Z-width: damping fractions must be in [0, 1)");
  if (!(options.relative_precision > 0.0 && options.relative_precision <= 1.0))
    throw Error("Z-width: the relative precision must be in (0, 1]");
  if (!options.without_passivity && !options.with_passivity)
    throw Error("Z-width: sweep with the passivity controller, without it, or both");

  std::vector<DeviceZWidth> results(devices.size());
  parallelFor(devices.size(), options.threads, [&](std::size_t i) {
    const ZWidthDevice& device = devices[i];
    DeviceZWidth& r = results[i];
    r.name = device.name;
    r.joint = device.joint;
    r.resolution = device.spec.position_resolution[device.joint];
    r.identification = identifyJoint(device);
    if (!r.identification.responds) {
      colgateBrownApplies(device, r.identification, options.script, &r.bound_note);
      return;
    }
    if (!(r.identification.inertia > 0.0) && device.make_free_space) {
      // The free-space control shapes the response (a null-space controller's stiffness outweighs the
      // inertia term): the inertia is the bare plant's.
      ZWidthDevice bare = device;
      bare.make_free_space = nullptr;
      const JointIdentification plant = identifyJoint(bare);
      if (plant.responds) r.identification.inertia = plant.inertia;
    }
    for (const double rate : options.rates_hz) {
      JointIdentification at_rate = identifyJoint(device, contactFrequencyHz(r.identification, rate));
      if (!at_rate.responds) at_rate = r.identification;
      at_rate.inertia = r.identification.inertia;  // measured at the default frequencies
      r.rate_identification.push_back(at_rate);
    }
    JointIdentification at_1khz = identifyJoint(device, contactFrequencyHz(r.identification, 1000.0));
    at_1khz.inertia = r.identification.inertia;
    r.bound_applies = colgateBrownApplies(device, at_1khz, options.script, &r.bound_note);
  });

  struct Task {
    std::size_t device;
    WallCase wall;
    std::size_t slot;
  };
  std::vector<Task> tasks;
  for (std::size_t i = 0; i < devices.size(); ++i) {
    DeviceZWidth& r = results[i];
    if (!r.identification.responds) {
      r.note = "the joint's motion does not follow its effort (a position-driven user moves it): no Z-width";
      continue;
    }
    for (const WallCase& c : zwidthCases(options, r.identification.damping)) {
      const bool known = std::find(r.skipped_rates_hz.begin(), r.skipped_rates_hz.end(), c.rate_hz) != r.skipped_rates_hz.end();
      if (known) continue;
      if (!plantResolvesPeriod(devices[i], 1.0 / c.rate_hz)) {
        r.skipped_rates_hz.push_back(c.rate_hz);
        continue;
      }
      tasks.push_back({i, c, r.boundaries.size()});
      r.boundaries.emplace_back();
    }
  }
  parallelFor(tasks.size(), options.threads, [&](std::size_t t) {
    const Task& task = tasks[t];
    const ZWidthDevice& device = devices[task.device];
    const DeviceZWidth& r = results[task.device];
    const auto at = std::find(options.rates_hz.begin(), options.rates_hz.end(), task.wall.rate_hz);
    const JointIdentification& id = r.rate_identification[static_cast<std::size_t>(at - options.rates_hz.begin())];
    std::unique_ptr<FreeSpaceControl> free_space = device.make_free_space ? device.make_free_space() : nullptr;
    // Start at the analytic bound (twice the spring's with the passivity controller), or at a tenth
    // of the spring's when the damper alone breaks the bound.
    WallCase spring = task.wall;
    spring.damping = 0.0;
    const double k_spring = analyticBounds(device, id, spring).k_colgate;
    double start = analyticBounds(device, id, task.wall).k_colgate;
    if (task.wall.passivity) start = 2.0 * k_spring;
    if (!(start > 0.0)) start = 0.1 * k_spring;
    results[task.device].boundaries[task.slot] = findBoundary(device, id, task.wall, start, options, free_space.get());
    if (on_boundary) on_boundary();
  });
  return results;
}

double boundaryStiffness(const DeviceZWidth& device, double rate_hz, int delay, bool passivity) noexcept {
  for (const Boundary& b : device.boundaries)
    if (std::abs(b.wall.rate_hz - rate_hz) <= 1e-9 * rate_hz && b.wall.delay == delay && b.wall.damping == 0.0 &&
        b.wall.passivity == passivity)
      return b.k_max;
  return std::numeric_limits<double>::quiet_NaN();
}

ZWidthDevice massDamperDevice(const MassDamperParams& params) {
  const auto finite = [](double x) { return std::isfinite(x); };
  if (!finite(params.inertia) || !(params.inertia > 0.0) || !finite(params.damping) || !(params.damping >= 0.0) ||
      !finite(params.centring) || !(params.centring >= 0.0) || !finite(params.effort_limit) ||
      !(params.effort_limit > 0.0))
    throw Error("massDamperDevice: inertia and effort limit must be > 0, damping and centring >= 0, all finite");
  ZWidthDevice d;
  d.name = "mass-damper";
  d.spec.descriptor.name = "1-DoF mass-damper";
  d.spec.descriptor.joints = 1;
  d.spec.descriptor.actuators = 1;
  d.spec.descriptor.effort_limit[0] = params.effort_limit;
  d.spec.servo_rate_hz = 1000.0;
  d.spec.sample_rate_hz = 1000.0;
  d.make_plant = [params](double) { return std::make_unique<MassDamperPlant>(params); };
  d.joint = 0;
  d.param_viscous = params.damping;
  d.param_coulomb = 0.0;
  return d;
}

}  // namespace uhaptics::experiments
