#include "uhaptics/experiments/task_zwidth.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <utility>

#include "uhaptics/backends/joint_io.hpp"
#include "uhaptics/core/fault.hpp"
#include "uhaptics/experiments/parallel.hpp"
#include "zwidth_common.hpp"

namespace uhaptics::experiments {

namespace {

using zwidth_detail::kPi;
using zwidth_detail::raisedCosine;
using zwidth_detail::searchStiffness;
using zwidth_detail::setBracket;
using zwidth_detail::ticksFor;
using zwidth_detail::Channels;
using zwidth_detail::HardwarePath;
using zwidth_detail::PeakToPeak;

// Identification: the sinusoidal force's amplitude [N], its smooth onset, the whole cycles measured.
constexpr double kTaskIdForce = 1.0;
constexpr double kTaskIdFrequencyHz = 20.0;
constexpr double kTaskIdOnsetS = 0.3;
constexpr int kTaskIdCycles = 10;
// As the joint harness: runaway and divergence in press depths.
constexpr double kTaskRunawayDepths = 50.0;
constexpr double kTaskDivergentDepths = 10.0;

// One plant under its policy as the CHAI3D adapter drives it: quantized joints, the board's rate
// estimator over the servo clock, the policy's efforts `delay` periods late; the user's force on the
// tool acts at once.
class TaskHarness {
 public:
  TaskHarness(const TaskZWidthDevice& device, const std::string& renderer, double period, int delay)
      : device_(device),
        plant_(device.make_plant ? device.make_plant(period) : nullptr),
        policy_(device.make_policy ? device.make_policy(renderer) : nullptr),
        path_(device.spec, period, delay) {
    if (!plant_ || !policy_) throw Error("task Z-width: device '" + device.name + "' has no plant or no policy");
    if (plant_->jointCount() != device.spec.descriptor.joints ||
        plant_->actuatorCount() != device.spec.descriptor.actuators)
      throw Error("task Z-width: device '" + device.name +
                  "': the plant's joint or actuator count differs from its spec");
    policy_->reset(delay);
    const Vec3 n = policy_->deviceToModelForce(device.normal);
    normal_model_ = n.norm() > 0.0 ? Vec3(n / n.norm()) : n;
  }

  // Reads the plant and senses through the policy; false when a reading is not finite.
  bool sense() noexcept {
    if (!path_.read(*plant_)) return false;
    policy_->sense(SensedJoints{path_.q().data(), path_.rates().data(), path_.tick() == 0}, state_);
    if (!plant_->readUserPoint(point_, velocity_)) return false;
    return state_.position.allFinite() && point_.allFinite() && velocity_.allFinite();
  }

  // One period: the policy's efforts for the scene's force (device frame), the user's force on the
  // tool (model frame). False when the plant reports a fault.
  bool step(const Vec3& scene_force, const Vec3& user_force) noexcept {
    SceneInput input;
    input.force = scene_force;
    input.seen_position = state_.position;
    input.dt = path_.period();
    input.time = static_cast<double>(path_.tick()) * path_.period();
    Channels command{};
    if (policy_->render(input, command.data()) != Fault::kNone) command.fill(0.0);
    const Channels applied = path_.command(command);
    plant_->applyCommand(applied.data());
    plant_->setUserForce(user_force);
    plant_->advance(path_.period());
    return plant_->lastFault() == Fault::kNone;
  }

  // The policy's efforts for a scene force at the last reading, without stepping the plant.
  bool probe(const Vec3& scene_force, Channels& efforts) noexcept {
    SceneInput input;
    input.force = scene_force;
    input.seen_position = state_.position;
    input.dt = path_.period();
    efforts.fill(0.0);
    return policy_->render(input, efforts.data()) == Fault::kNone;
  }

  // The tool along n, true [m] and sensed (device frame) [m]; velocity along n [m/s].
  double along() const noexcept { return normal_model_.dot(point_); }
  double sensedAlong() const noexcept { return device_.normal.dot(state_.position); }
  const Vec3& velocity() const noexcept { return velocity_; }
  // n in the plant's task frame, where the user's force acts.
  const Vec3& normalModel() const noexcept { return normal_model_; }

 private:
  const TaskZWidthDevice& device_;
  std::unique_ptr<BoardPlant> plant_;
  std::unique_ptr<DevicePolicy> policy_;
  HardwarePath path_;
  SensedState state_;
  Vec3 point_ = Vec3::Zero(), velocity_ = Vec3::Zero(), normal_model_ = Vec3::UnitZ();
};

void checkCase(double rate_hz, int delay) {
  if (!(rate_hz > 0.0) || !std::isfinite(rate_hz)) throw Error("task Z-width: the servo rate must be > 0");
  if (delay < 0 || delay > kMaxZWidthDelay) throw Error("task Z-width: the command delay must be in 0..3 periods");
}

// What a sinusoidal force along -n puts in over whole cycles, with the hand's damper on.
struct TaskExcitation {
  bool ok = false;
  double work = 0.0;      // sum F dx_n [J]
  double rate2 = 0.0;     // sum dx_n^2 / T [m^2/s]
  double in_phase = 0.0;  // Re(F / x_n) = k - m w^2 [N/m]
};

TaskExcitation exciteTask(const TaskZWidthDevice& device, double period, double frequency_hz) {
  TaskHarness harness(device, device.renderers.front(), period, 0);
  const long onset = ticksFor(kTaskIdOnsetS, period);
  const long n = onset + ticksFor(kTaskIdCycles / frequency_hz, period);
  const double omega = 2.0 * kPi * frequency_hz;
  TaskExcitation e;
  std::vector<double> x, force;
  x.reserve(static_cast<std::size_t>(n + 1));
  force.reserve(static_cast<std::size_t>(n + 1));
  double previous_x = 0.0, previous_f = 0.0;
  for (long k = 0; k <= n; ++k) {
    if (!harness.sense()) return e;
    const double xn = harness.along();
    x.push_back(xn);
    if (k > onset) {
      const double dx = xn - previous_x;
      e.work += previous_f * dx;
      e.rate2 += dx * dx / period;
    }
    if (k == n) break;
    const double t = static_cast<double>(k) * period;
    const double f = kTaskIdForce * raisedCosine(t / kTaskIdOnsetS) * std::sin(omega * t);
    force.push_back(f);
    const Vec3 user = f * harness.normalModel() - device.hand_damping * harness.velocity();
    if (!harness.step(Vec3::Zero(), user)) return e;
    previous_x = xn;
    previous_f = f;
  }
  double mean = 0.0;
  for (long k = onset; k < n; ++k) mean += x[static_cast<std::size_t>(k)];
  mean /= static_cast<double>(n - onset);
  double cross = 0.0, square = 0.0;
  for (long k = onset; k < n; ++k) {
    const double dev = x[static_cast<std::size_t>(k)] - mean;
    cross += force[static_cast<std::size_t>(k)] * dev;
    square += dev * dev;
  }
  e.in_phase = square > 0.0 ? cross / square : 0.0;
  e.ok = e.rate2 > 0.0;
  return e;
}

TaskIdentification identifyAt(const TaskZWidthDevice& device, double period, double frequency_hz) {
  TaskIdentification id;
  const TaskExcitation e = exciteTask(device, period, frequency_hz);
  if (!e.ok) return id;
  id.responds = true;
  id.damping = e.work / e.rate2;
  id.frequency_hz = frequency_hz;
  return id;
}

// Where the contact mode rings at the spring's bound 2 b / T, as contactFrequencyHz().
double taskContactFrequencyHz(const TaskIdentification& id, double rate_hz) noexcept {
  if (!(id.mass > 0.0) || !(id.damping > 0.0)) return kTaskIdFrequencyHz;
  const double f = std::sqrt(2.0 * id.damping * rate_hz / id.mass) / (2.0 * kPi);
  return std::clamp(f, 5.0, rate_hz / 10.0);
}

}  // namespace

TaskIdentification identifyTask(const TaskZWidthDevice& device, double frequency_hz) {
  if (!(frequency_hz >= 0.0) || !std::isfinite(frequency_hz))
    throw Error("task Z-width: the identification frequency must be >= 0");
  const double f1 = frequency_hz > 0.0 ? frequency_hz : kTaskIdFrequencyHz;
  const double period = 1e-3;
  const TaskExcitation first = exciteTask(device, period, f1);
  const TaskExcitation second = exciteTask(device, period, 2.0 * f1);
  TaskIdentification id;
  if (!first.ok || !second.ok) return id;
  const double w1 = 2.0 * kPi * f1, w2 = 2.0 * w1;
  id.responds = true;
  id.damping = first.work / first.rate2;
  id.mass = (first.in_phase - second.in_phase) / (w2 * w2 - w1 * w1);
  id.frequency_hz = f1;
  return id;
}

double forceCapacity(const TaskZWidthDevice& device) {
  TaskHarness harness(device, device.renderers.front(), 1.0 / device.spec.servo_rate_hz, 0);
  Channels rest{}, pushed{};
  if (!harness.sense() || !harness.probe(Vec3::Zero(), rest) || !harness.probe(device.normal, pushed))
    throw Error("task Z-width: device '" + device.name + "': its policy renders nothing at the start pose");
  double capacity = std::numeric_limits<double>::infinity();
  for (int a = 0; a < device.spec.descriptor.actuators; ++a) {
    const double per_newton = std::abs(pushed[a] - rest[a]);
    const double headroom = device.spec.descriptor.effort_limit[a] - std::abs(rest[a]);
    if (per_newton > 0.0) capacity = std::min(capacity, std::max(0.0, headroom) / per_newton);
  }
  return capacity;
}

TaskWallRun runTaskWall(const TaskZWidthDevice& device, const std::string& renderer, double rate_hz, int delay,
                        double stiffness, const TaskScript& script, double capacity) {
  checkCase(rate_hz, delay);
  if (!(stiffness > 0.0) || !std::isfinite(stiffness)) throw Error("task Z-width: the wall stiffness must be > 0");
  const double T = 1.0 / rate_hz;
  if (!(capacity > 0.0)) capacity = forceCapacity(device);
  const double press =
      std::min({stiffness * script.press_depth, script.max_press_force, script.press_capacity_fraction * capacity});
  const double depth = press / stiffness;

  const double t_press = script.settle_s;
  const double t_kick = t_press + script.press_ramp_s;
  const double t_hold = t_kick + script.kick_s;
  const double t_release = t_hold + script.hold_s;
  const double t_free = t_release + script.release_ramp_s;
  const long n = ticksFor(t_free + script.after_s, T);
  const long n_press = ticksFor(t_press, T);
  const long n_release = ticksFor(t_release, T);
  const long n_hold_window = n_release - ticksFor(script.final_window_s, T);
  const long n_early = ticksFor(t_hold + script.early_window_s, T);
  const long n_early_end = n_early + ticksFor(script.final_window_s, T);
  const long n_window = n - ticksFor(script.final_window_s, T);
  const double base = (1.0 - script.kick_fraction) * press;
  const auto pressing = [&](double t) {
    if (t < t_press) return 0.0;
    if (t < t_kick) return base * raisedCosine((t - t_press) / script.press_ramp_s);
    if (t < t_hold) return base + (press - base) * raisedCosine((t - t_kick) / script.kick_s);
    if (t < t_release) return press;
    if (t < t_free) return press * (1.0 - raisedCosine((t - t_release) / script.release_ramp_s));
    return 0.0;
  };

  TaskHarness harness(device, renderer, T, delay);
  TaskWallRun run;
  run.stiffness = stiffness;
  run.press_force = press;
  bool diverged = false, inside = false;
  double wall = 0.0, wall_true = 0.0, previous_x = 0.0, previous_f = 0.0, user_work = 0.0;
  PeakToPeak window, hold, early;
  double hold_sum = 0.0;
  long hold_count = 0;
  for (long k = 0; k <= n; ++k) {
    if (!harness.sense()) {
      diverged = true;
      break;
    }
    const double x = harness.along();
    if (k > 0) user_work += -previous_f * (x - previous_x);  // the press acts along -n
    if (k == n_press) {  // the wall's plane through the tool at rest
      wall = harness.sensedAlong();
      wall_true = x;
    }
    if (k >= n_early && k < n_early_end) {
      early.add(x);
    }
    if (k >= n_hold_window && k < n_release) {
      hold.add(x);
    }
    if (k >= n_window) {
      window.add(x);
    }
    if (k == n) break;

    Vec3 scene = Vec3::Zero();
    if (k >= n_press) {
      const double p = wall - harness.sensedAlong();
      if (std::abs(wall_true - x) > kTaskRunawayDepths * std::max(depth, script.press_depth)) {
        diverged = true;
        break;
      }
      if (p > 0.0) {
        scene = stiffness * p * device.normal;
        if (!inside && k >= n_hold_window && k < n_release) ++run.hold_entries;
        if (!inside && k >= n_window) ++run.final_entries;
      }
      inside = p > 0.0;
      run.max_penetration = std::max(run.max_penetration, wall_true - x);
      if (k >= n_hold_window && k < n_release) {
        hold_sum += p;
        ++hold_count;
      }
    }
    const double f = pressing(static_cast<double>(k) * T);
    const Vec3 user = -f * harness.normalModel() - device.hand_damping * harness.velocity();
    if (!harness.step(scene, user)) {
      diverged = true;
      break;
    }
    previous_x = x;
    previous_f = f;
  }
  run.generated_energy = -user_work;
  run.final_amplitude = window.width();
  run.hold_amplitude = hold.width();
  run.early_amplitude = early.width();
  run.hold_penetration = hold_count > 0 ? hold_sum / static_cast<double>(hold_count) : 0.0;
  if (run.hold_penetration > 0.0) run.rendered_stiffness = press / run.hold_penetration;
  const double peak = std::max(run.max_penetration, depth);
  run.tolerance = script.relative_tolerance * 0.5 * stiffness * peak * peak;
  const double wide = kTaskDivergentDepths * script.press_depth;
  // One count flickering across the wall's surface is not a bounce.
  const double flicker = 0.02 * depth;
  if (diverged || !std::isfinite(run.generated_energy) || run.hold_amplitude > wide || run.final_amplitude > wide)
    run.outcome = WallOutcome::kDivergent;
  // Bouncing, or the kick's ring not decaying over the hold (the contact mode's net damping
  // b_n - K T / 2 <= 0: it grows until the tool bounces, later than the run sees near the boundary).
  // Rings at a quantized sensor's noise floor are neither.
  else if ((run.hold_entries >= 2 && run.hold_amplitude > flicker) ||
           (run.final_entries >= 2 && run.final_amplitude > flicker) ||
           (run.early_amplitude > 5.0 * flicker && run.hold_amplitude >= run.early_amplitude))
    run.outcome = WallOutcome::kLimitCycle;
  else if (run.generated_energy > run.tolerance)
    run.outcome = WallOutcome::kActive;
  else
    run.outcome = WallOutcome::kPassive;
  return run;
}

TaskBoundary findTaskBoundary(const TaskZWidthDevice& device, const std::string& renderer, double rate_hz, int delay,
                              double start_k, const TaskZWidthOptions& options) {
  const double capacity = forceCapacity(device);
  TaskBoundary out;
  out.renderer = renderer;
  out.rate_hz = rate_hz;
  out.delay = delay;
  const auto passive = [&](double k) {
    out.runs.push_back(runTaskWall(device, renderer, rate_hz, delay, k, options.script, capacity));
    return out.runs.back().outcome == WallOutcome::kPassive;
  };
  const double k0 = start_k > 0.0 && std::isfinite(start_k) ? start_k : 100.0;
  setBracket(out, searchStiffness(passive, k0, options.max_bracket_steps, options.relative_precision));
  double unstable = std::numeric_limits<double>::infinity();
  for (const TaskWallRun& run : out.runs) {
    if (run.stiffness == out.k_max) out.rendered_stiffness = run.rendered_stiffness;
    if (run.outcome == WallOutcome::kLimitCycle || run.outcome == WallOutcome::kDivergent)
      unstable = std::min(unstable, run.stiffness);
  }
  for (const TaskWallRun& run : out.runs)
    if (run.stiffness < unstable && !(run.stiffness <= out.k_stable)) {
      out.k_stable = run.stiffness;
      out.rendered_stable = run.rendered_stiffness;
      out.energy_stable = run.generated_energy;
    }
  return out;
}

std::vector<DeviceTaskZWidth> sweepTaskZWidth(const std::vector<TaskZWidthDevice>& devices,
                                              const TaskZWidthOptions& options,
                                              const std::function<void()>& on_boundary) {
  if (options.rates_hz.empty() || options.delays.empty()) throw Error("task Z-width: no rate or no delay to sweep");
  for (const double r : options.rates_hz) checkCase(r, 0);
  for (const int d : options.delays) checkCase(1000.0, d);
  if (!(options.relative_precision > 0.0 && options.relative_precision <= 1.0))
    throw Error("task Z-width: the relative precision must be in (0, 1]");

  // Identification: the mass at 1 kHz, then b_n at each rate's contact frequency and period.
  std::vector<DeviceTaskZWidth> results(devices.size());
  std::vector<std::vector<TaskIdentification>> at_rate(devices.size());
  parallelFor(devices.size(), options.threads, [&](std::size_t i) {
    const TaskZWidthDevice& device = devices[i];
    DeviceTaskZWidth& r = results[i];
    r.name = device.name;
    r.normal = device.normal;
    r.hand_damping = device.hand_damping;
    r.note = device.skip_note;
    if (!r.note.empty()) return;
    r.force_capacity = forceCapacity(device);
    r.identification = identifyTask(device);
    if (!r.identification.responds) {
      r.note = "the tool does not follow the user's force";
      return;
    }
    for (const double rate : options.rates_hz) {
      TaskIdentification id = identifyAt(device, 1.0 / rate, taskContactFrequencyHz(r.identification, rate));
      if (!id.responds) id = r.identification;
      id.mass = r.identification.mass;
      at_rate[i].push_back(id);
    }
  });

  struct Task {
    std::size_t device, slot;
    std::string renderer;
    double rate_hz;
    int delay;
    double b_n;
  };
  std::vector<Task> tasks;
  for (std::size_t i = 0; i < devices.size(); ++i) {
    if (!results[i].note.empty()) continue;
    const std::vector<std::string>& native = devices[i].native_rate_renderers;
    for (const std::string& renderer : devices[i].renderers)
      for (std::size_t k = 0; k < options.rates_hz.size(); ++k)
        for (const int d : options.delays) {
          const bool native_only = std::find(native.begin(), native.end(), renderer) != native.end();
          if (native_only && std::abs(options.rates_hz[k] - devices[i].spec.servo_rate_hz) > 1e-9 * options.rates_hz[k])
            continue;
          tasks.push_back({i, results[i].boundaries.size(), renderer, options.rates_hz[k], d, at_rate[i][k].damping});
          results[i].boundaries.emplace_back();
        }
  }
  parallelFor(tasks.size(), options.threads, [&](std::size_t t) {
    const Task& task = tasks[t];
    const double k_colgate = std::max(0.0, 2.0 * task.b_n * task.rate_hz / (1.0 + 2.0 * task.delay));
    TaskBoundary b =
        findTaskBoundary(devices[task.device], task.renderer, task.rate_hz, task.delay, k_colgate, options);
    b.b_n = task.b_n;
    b.k_colgate = k_colgate;
    results[task.device].boundaries[task.slot] = std::move(b);
    if (on_boundary) on_boundary();
  });
  return results;
}

namespace {

// The closed-form check's plant and "policy": a point mass along device z, forces straight through.
class PointMassTaskPlant final : public BoardPlant {
 public:
  PointMassTaskPlant(double mass, double damping) noexcept : m_(mass), b_(damping) {}
  int jointCount() const noexcept override { return 1; }
  int actuatorCount() const noexcept override { return 1; }
  void readJoints(double* positions) noexcept override { positions[0] = x_; }
  void applyCommand(const double* efforts) noexcept override { u_ = std::isfinite(efforts[0]) ? efforts[0] : 0.0; }
  void advance(double dt) noexcept override {
    if (!(dt > 0.0) || !std::isfinite(dt)) return;
    // Exact for a constant force over the step (the held command and the held user force).
    const double f = u_ + user_, a = b_ / m_, e = std::exp(-a * dt);
    const double v_inf = f / b_;
    x_ += v_inf * dt + (v_ - v_inf) * (1.0 - e) / a;
    v_ = v_inf + (v_ - v_inf) * e;
  }
  bool readUserPoint(Vec3& position, Vec3& velocity) noexcept override {
    position = Vec3(0.0, 0.0, x_);
    velocity = Vec3(0.0, 0.0, v_);
    return true;
  }
  void setUserForce(const Vec3& force) noexcept override { user_ = std::isfinite(force.z()) ? force.z() : 0.0; }

 private:
  double m_, b_;
  double x_ = 0.0, v_ = 0.0, u_ = 0.0, user_ = 0.0;
};

class PointMassPolicy final : public DevicePolicy {
 public:
  std::string name() const override { return "spring"; }
  void reset(int) override {}
  void sense(const SensedJoints& reading, SensedState& state) noexcept override {
    state.position = Vec3(0.0, 0.0, reading.positions[0]);
    state.linear_velocity = Vec3(0.0, 0.0, reading.rates[0]);
  }
  Fault render(const SceneInput& input, double* efforts) noexcept override {
    efforts[0] = input.force.z();
    return Fault::kNone;
  }
};

}  // namespace

ReproductionTable taskZWidthReproduction(const std::vector<TaskZWidthDevice>& devices,
                                         const std::vector<DeviceTaskZWidth>& results) {
  if (devices.size() != results.size()) throw Error("task Z-width: one result per device expected");
  ReproductionTable table;
  char quantity[200];
  for (std::size_t i = 0; i < devices.size(); ++i) {
    const TaskZWidthDevice& device = devices[i];
    const DeviceTaskZWidth& r = results[i];
    if (!r.note.empty()) continue;
    const bool bound_applies = !device.coulomb_friction && r.identification.mass > 0.0;
    for (const TaskBoundary& b : r.boundaries) {
      if (!bound_applies || b.renderer != "spring" || b.delay != 0 || b.rate_hz > 1000.0 || !(b.k_colgate > 0.0))
        continue;
      std::snprintf(quantity, sizeof quantity, "%s at the tool, %g kHz: spring wall's K_max / (2 b_n / T)",
                    r.name.c_str(), b.rate_hz / 1000.0);
      const double ratio = b.above_range ? std::numeric_limits<double>::infinity() : b.k_max / b.k_colgate;
      table.add({kStabilityRows, quantity, 1.0, ratio, "within 10 % of Colgate-Brown", false, "", {},
                 Accepted::within(1.0, 0.10)});
    }
    for (const int delay : {0, 1}) {
      const RatedStiffness& rated = delay == 0 ? device.spec.rated_stiffness : device.spec.rated_stiffness_delayed;
      // The ratio farthest from the interval's centre: too close to the boundary or too far below it.
      double worst = 0.75;
      bool any = false;
      for (std::size_t k = 0; k < rated.size(); ++k) {
        if (!std::isfinite(rated[k])) continue;
        for (const TaskBoundary& b : r.boundaries)
          if (b.renderer == "spring" && b.delay == delay && b.rate_hz == kRatedServoRatesHz[k]) {
            any = true;
            // A boundary not found (NaN) fails the row, as it should.
            const double ratio = std::isfinite(b.k_max) ? rated[k] / b.k_max : std::nan("");
            if (!std::isnan(worst) && !(std::abs(ratio - 0.75) <= std::abs(worst - 0.75))) worst = ratio;
          }
      }
      if (!any) continue;
      std::snprintf(quantity, sizeof quantity,
                    "%s: rated m_maxLinearStiffness / measured K_max at the tool, worst of 0.5-4 kHz, delay %d",
                    r.name.c_str(), delay);
      table.add({kStabilityRows, quantity, 0.8, worst, "within [0.5, 1]: inside the passive region", false, "", {},
                 Accepted::within(0.75, 0.25)});
    }
  }
  return table;
}

bool TaskLayerCheck::pass() const noexcept {
  return layered.outcome == WallOutcome::kPassive && layered.rendered_stiffness >= 0.8 * stiffness &&
         observed.outcome != WallOutcome::kPassive;
}

std::vector<TaskLayerCheck> checkPassivityLayer(const std::vector<TaskZWidthDevice>& devices,
                                                const std::vector<DeviceTaskZWidth>& results, double rate_hz,
                                                const TaskScript& script) {
  if (devices.size() != results.size()) throw Error("task Z-width: one result per device expected");
  std::vector<TaskLayerCheck> checks;
  for (std::size_t i = 0; i < devices.size(); ++i) {
    const TaskZWidthDevice& device = devices[i];
    const std::string layered = std::string("spring") + kPassivitySuffix;
    if (std::find(device.renderers.begin(), device.renderers.end(), layered) == device.renderers.end()) continue;
    for (const TaskBoundary& b : results[i].boundaries) {
      if (b.renderer != "spring" || b.rate_hz != rate_hz || !std::isfinite(b.k_max)) continue;
      TaskLayerCheck c;
      c.device = device.name;
      c.rate_hz = rate_hz;
      c.delay = b.delay;
      c.k_without = b.k_max;
      c.stiffness = 2.0 * b.k_max;
      c.layered = runTaskWall(device, layered, rate_hz, b.delay, c.stiffness, script);
      c.observed = runTaskWall(device, std::string("spring") + kObservedPassivitySuffix, rate_hz, b.delay, c.stiffness,
                               script);
      checks.push_back(c);
    }
  }
  return checks;
}

ReproductionTable passivityLayerReproduction(const std::vector<TaskLayerCheck>& checks) {
  ReproductionTable table;
  char quantity[200];
  for (const TaskLayerCheck& c : checks) {
    std::snprintf(quantity, sizeof quantity,
                  "%s at the tool, %g kHz, delay %d: spring wall at 2 K_max with passivity=1, rendered / K", c.device.c_str(),
                  c.rate_hz / 1000.0, c.delay);
    table.add({kStabilityRows, quantity, 1.0, c.layered.rendered_stiffness / c.stiffness,
               "passive and >= 0.8; with passivity=2 not passive", c.pass(), ""});
  }
  return table;
}

TaskZWidthDevice pointMassTaskDevice(double mass, double damping) {
  if (!(mass > 0.0) || !(damping > 0.0) || !std::isfinite(mass) || !std::isfinite(damping))
    throw Error("pointMassTaskDevice: mass and damping must be finite and > 0");
  TaskZWidthDevice d;
  d.name = "point-mass";
  d.spec.descriptor.name = "1-DoF point mass";
  d.spec.descriptor.joints = 1;
  d.spec.descriptor.actuators = 1;
  d.spec.descriptor.effort_limit[0] = 1e3;
  d.spec.servo_rate_hz = 1000.0;
  d.spec.sample_rate_hz = 1000.0;
  d.make_plant = [mass, damping](double) { return std::make_unique<PointMassTaskPlant>(mass, damping); };
  d.make_policy = [](const std::string&) { return std::make_unique<PointMassPolicy>(); };
  d.normal = Vec3::UnitZ();
  return d;
}

}  // namespace uhaptics::experiments
