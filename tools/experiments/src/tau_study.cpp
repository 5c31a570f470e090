#include "uhaptics/experiments/tau_study.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <mutex>
#include <random>
#include <utility>

#include "uhaptics/experiments/parallel.hpp"

namespace uhaptics::study {

const char* name(Controller c) { return c == Controller::kLqr ? "lqr" : "spring"; }

namespace {

// Hand trajectory of eq. 15: accelerate toward the wall for 0.45 s, coast 0.1 s, decelerate 0.45 s.
// Travel = a_c (0.45^2 + 0.45 * 0.1) = 0.2475 a_c; with the tool held at the wall the final hand
// force is k_h * travel = F_c, which fixes a_c.
double handAcceleration(double t, double a_c) {
  if (t >= 1.0 && t < 1.45) return -a_c;
  if (t >= 1.55 && t < 2.0) return a_c;
  return 0.0;
}

}  // namespace

TauPolicy::WallDesign studyWallDesign(const LqrWallWeights& weights, double contact_band) {
  TauPolicy::WallDesign design;
  design.weights = weights;
  // Paper 001's controller: the whole pose held at the contact point, bilaterally.
  design.renderer.follow_tangentially = false;
  design.renderer.unilateral = false;
  design.renderer.keep_direction = false;
  // The wall's own 0.2 mm release is for interactive, unilateral use; the study holds while the
  // environment reports the contact (a delayed loop bounces the tool above 0.2 mm after the step).
  design.renderer.release_distance = contact_band;
  return design;
}

namespace {
TauPolicy& tauPolicy(DevicePolicy* policy) {
  auto* tau = dynamic_cast<TauPolicy*>(policy);
  if (tau == nullptr) throw Error("study: the device's policy factory did not make the TAU's policy");
  return *tau;
}
}  // namespace

StudyDevice::StudyDevice(const TauProduct& product, const TauPolicy::WallDesign& design, int command_delay)
    : policy_(product.make_policy ? product.make_policy() : nullptr),
      tau_(&tauPolicy(policy_.get())),
      servo_(*policy_, product.spec),
      command_delay_(command_delay) {
  tau_->setWallDesign(design);
  servo_.reset(command_delay_);  // designs the wall once, here
}

RunMetrics simulateRun(const TauModel& model, StudyDevice& device, const RunSpec& spec, const StudyParameters& params,
                       std::vector<TraceSample>* trace) {
  std::mt19937_64 rng(spec.seed);
  RunMetrics m;
  m.force_level = std::uniform_real_distribution<double>(params.force_min, params.force_max)(rng);
  std::normal_distribution<double> noise(0.0, params.noise_sigma);

  const bool lqr_wall = spec.controller == Controller::kLqr;
  SimulatedTauOptions so;
  so.max_delay_samples = spec.max_delay_samples;
  so.quantize = spec.quantize;
  so.substeps = spec.substeps;
  so.relinearize_tolerance = spec.relinearize_tolerance;
  so.seed = spec.seed ^ 0x9e3779b97f4a7c15ULL;
  so.tool_damping = lqr_wall ? 0.0 : params.device_damping;
  so.tool_rotational_damping = lqr_wall ? 0.0 : params.device_rotational_damping;
  SimulatedTau sim(model, so);
  Vec6 start_pose = model.homePose();
  start_pose(0) = spec.x;
  start_pose(1) = spec.y;
  start_pose(2) = 0.0;  // in contact with the wall, no interaction force (paper section V)
  Vec6 q0;
  if (model.inverse(start_pose, q0) != Fault::kNone) throw Error("study: query point outside the workspace");
  sim.reset(q0);

  TauPolicy& policy = device.policy();
  experiments::PolicyServo& servo = device.servo();
  policy.setWallMode(lqr_wall ? TauPolicy::WallMode::kAuto : TauPolicy::WallMode::kSpring);
  policy.clearContactSurface();
  servo.reset(device.commandDelay());
  // The scene: the wall z = 0 of the model frame, in the device frame the policy reports.
  const Vec3 normal = Vec3::UnitZ();
  const Vec3 wall_point = policy.modelToDevicePoint(Vec3::Zero());
  Referee referee;

  const double T = model.servoPeriod();
  const int steps = static_cast<int>(std::lround(spec.duration / T));
  const double a_c = m.force_level / (so.hand.stiffness * 0.2475);
  const bool hand = spec.scenario == Scenario::kHand;
  const double disturbance_start = 1.0;
  const double steady_start = hand ? 2.0 : 1.0;  // paper: steady stage 1-3 s (sc. 1), 2-3 s (sc. 2)
  const double noise_start = hand ? 2.0 : 1.0;
  double steady_sum = 0.0;
  int steady_n = 0;
  // First impact: the largest penetration within the impact window after the disturbance starts
  // (scenario 1: 0.3 s, several times the baseline's first oscillation period; scenario 2: the
  // whole 1 s ramp of the hand force).
  const double impact_end = disturbance_start + (hand ? 1.0 : 0.3);
  Vec3 hand_p = start_pose.head<3>(), hand_v = Vec3::Zero();
  Vec6 efforts = Vec6::Zero();
  for (int k = 0; k < steps; ++k) {
    const double t = k * T;
    // What the board senses: the encoders, and which command acted over the last period.
    const int applied_age = spec.applied_command_reported && k > 0 ? sim.appliedDelay() : -1;
    const SensedState& sensed = servo.sense(sim.encoderReading().data(), applied_age);
    // The scene: a spring wall that reports its surface while the tool is within the contact band.
    const double depth = (wall_point - sensed.position).dot(normal);
    const Vec3 force = params.spring_stiffness * std::max(0.0, depth) * normal;
    if (lqr_wall) {
      const Vec3 surface_point(sensed.position.x(), sensed.position.y(), wall_point.z());
      policy.setContactSurface(-depth <= params.contact_band, surface_point, normal);
    }
    const Fault rendered = servo.render(force, efforts.data());
    if (rendered != Fault::kNone && m.fault == Fault::kNone) {
      m.fault = rendered;
      m.fault_time = t;
    }
    m.max_torque = std::max(m.max_torque, efforts.cwiseAbs().maxCoeff());

    const double noise_now = t >= noise_start ? noise(rng) : 0.0;
    Vec3 external = Vec3::Zero();
    if (hand) {
      const double a = handAcceleration(t, a_c);
      sim.setHand(hand_p, hand_v, Vec3(0, 0, a));
      hand_p += hand_v * T + Vec3(0, 0, 0.5 * a * T * T);
      hand_v += Vec3(0, 0, a * T);
      external.z() = -noise_now;
    } else if (t >= disturbance_start) {
      external.z() = -(m.force_level + noise_now);
    }
    const Fault sf = sim.step(efforts, external);
    if (sf != Fault::kNone) {
      m.fault = sf;
      m.fault_time = t;
      m.fault_in_plant = true;
      break;
    }
    // The truth, for the metrics and the referee only.
    RefereeSample sample;
    sample.dt = T;
    sample.truth.position = sim.pose().head<3>();
    sample.truth.velocity = sim.toolVelocity();
    sample.truth.user_force = (hand ? sim.handForce() : Vec3::Zero()) + external;
    sample.truth.applied_force = sim.toolForce();
    sample.truth.saturated =
        (sim.appliedTorque().cwiseAbs().array() >= (1.0 - 1e-9) * model.effortLimits().array()).any();
    sample.asked_force = policy.deviceToModelForce(force);
    referee.observe(sample);
    m.saturated_ticks += sample.truth.saturated ? 1 : 0;

    const double push = hand ? -sim.handForce().z() + noise_now : -external.z();
    const double tn = t + T;
    const double pen = std::max(0.0, -sim.pose()(2));
    m.max_penetration = std::max(m.max_penetration, pen);
    if (tn > disturbance_start && tn <= impact_end && pen > m.d_z1) {
      m.d_z1 = pen;
      m.t_z1 = tn;
      m.k_z1 = push;  // divided below
    }
    if (tn > steady_start) {
      steady_sum += pen;
      ++steady_n;
    }
    if (trace) trace->push_back({tn, sim.pose()(2), push, efforts(5), policy.lqrEngaged() ? 1 : 0});
  }
  policy.clearContactSurface();
  m.referee = referee.report();
  m.k_z1 = m.k_z1 / std::max(m.d_z1, params.min_penetration);
  m.d_zs = steady_n > 0 ? steady_sum / steady_n : 0.0;
  m.k_zs = m.force_level / std::max(m.d_zs, params.min_penetration);
  return m;
}

namespace {

// The LQR joint regulator of eq. 11 (u = g(q) - Kc x - Ki x_i, x_i' = r - q, x measured from the
// equilibrium held at the start) on the ideal-sensor simulator: what the paper's requirement checks
// exercise. Calls back with each state.
template <typename Observe>
void regulate(const TauModel& model, const LqrWallGains& gains, Feedback feedback, const Vec6& start_q,
              const Vec6& reference, double duration, double force_time, double force, Observe&& observe) {
  SimulatedTauOptions so;
  so.quantize = feedback == Feedback::kObserverOnEncoders;
  SimulatedTau sim(model, so);
  sim.reset(start_q);
  TauData data(model);
  data.pose = sim.pose();
  LqrJointRegulator regulator(gains);
  regulator.reset(start_q);
  const double T = model.servoPeriod();
  const int steps = static_cast<int>(std::lround(duration / T));
  for (int k = 0; k < steps; ++k) {
    const Vec6& q = sim.encoderReading();
    if (model.forward(q, data) != Fault::kNone) throw Error("study: forward kinematics failed in a requirement check");
    model.computeGravity(q, data);
    regulator.observe(q);
    const bool state = feedback == Feedback::kState;
    Vec<12> x;
    x.head<6>() = state ? sim.qd() : regulator.velocity();
    x.tail<6>() = (state ? sim.q() : regulator.position()) - start_q;
    const Vec6 tau = data.gravity + regulator.control(x);
    regulator.integrate(x.tail<6>() + start_q - reference);
    regulator.applied(tau);
    const double t = k * T;
    sim.step(tau, Vec3(0, 0, t >= force_time ? -force : 0.0));
    observe(t + T, sim);
  }
}

}  // namespace

StepResponse stepReferenceResponse(const TauModel& model, const LqrWallGains& gains, const Vec6& pose, double step,
                                   Feedback feedback) {
  Vec6 q0, r;
  Vec6 target = pose;
  target(2) += step;
  if (model.inverse(pose, q0) != Fault::kNone || model.inverse(target, r) != Fault::kNone)
    throw Error("study: step reference outside the workspace");
  std::vector<std::pair<double, double>> z;
  regulate(model, gains, feedback, q0, r, 0.5, 1e9, 0.0, [&](double t, const SimulatedTau& sim) {
    z.emplace_back(t, (sim.pose()(2) - pose(2)) / step);  // normalized response, 1 = target
  });
  StepResponse out;
  double t10 = -1, t90 = -1, peak = 0.0;
  for (const auto& [t, y] : z) {
    if (t10 < 0 && y >= 0.1) t10 = t;
    if (t90 < 0 && y >= 0.9) t90 = t;
    peak = std::max(peak, y);
    if (std::abs(y - 1.0) > 0.02) out.settling_time = t;
  }
  out.overshoot_percent = std::max(0.0, (peak - 1.0) * 100.0);
  out.rise_time = (t10 >= 0 && t90 >= 0) ? t90 - t10 : std::numeric_limits<double>::infinity();
  return out;
}

double forceStepDeviation(const TauModel& model, const LqrWallGains& gains, const Vec6& pose, double force,
                          Feedback feedback) {
  Vec6 r;
  if (model.inverse(pose, r) != Fault::kNone) throw Error("study: force-step pose outside the workspace");
  double worst = 0.0;
  regulate(model, gains, feedback, r, r, 0.6, 0.1, force, [&](double, const SimulatedTau& sim) {
    worst = std::max(worst, (sim.q() - r).cwiseAbs().maxCoeff());
  });
  return worst;
}

Requirements checkRequirements(const TauModel& model, const LqrWallGains& gains) {
  Requirements r;
  r.step = stepReferenceResponse(model, gains, model.homePose(), 1e-3);
  r.deviation = forceStepDeviation(model, gains, model.homePose(), 15.0);
  r.deviation_encoders = forceStepDeviation(model, gains, model.homePose(), 15.0, Feedback::kObserverOnEncoders);
  return r;
}

// ---- the study over the wall -----------------------------------------------------------------------
const std::array<Variant, kNumVariants>& studyVariants() {
  static const std::array<Variant, kNumVariants> kVariants = {{
      {Controller::kLqr, Scenario::kStepForce, 0, "lqr_s1"},
      {Controller::kSpring, Scenario::kStepForce, 0, "spring_s1"},
      {Controller::kLqr, Scenario::kHand, 0, "lqr_s2"},
      {Controller::kSpring, Scenario::kHand, 0, "spring_s2"},
      {Controller::kLqr, Scenario::kStepForce, 3, "lqr_s1_delay"},
      {Controller::kLqr, Scenario::kHand, 3, "lqr_s2_delay"},
  }};
  return kVariants;
}

std::uint64_t runSeed(std::uint64_t base_seed, std::size_t job) {
  std::uint64_t z = base_seed * 0x9e3779b97f4a7c15ULL + job + 0x632be59bd9b4e019ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

Statistics statistics(const std::vector<double>& v) {
  Statistics s;
  s.min = std::numeric_limits<double>::infinity();
  s.max = -std::numeric_limits<double>::infinity();
  for (double x : v) {
    s.mean += x;
    s.min = std::min(s.min, x);
    s.max = std::max(s.max, x);
  }
  s.mean /= static_cast<double>(v.size());
  for (double x : v) s.stddev += (x - s.mean) * (x - s.mean);
  s.stddev = v.size() > 1 ? std::sqrt(s.stddev / static_cast<double>(v.size() - 1)) : 0.0;
  return s;
}

namespace {
// One worker's devices: the undelayed variants' and the delay variants'.
struct WorkerDevices {
  StudyDevice undelayed, delayed;
  WorkerDevices(const TauProduct& product, const StudyDesigns& designs)
      : undelayed(product, designs.undelayed, 0), delayed(product, designs.delayed, designs.delay_samples) {}
};

// Devices handed to the jobs, each used by one job at a time: a policy is single-threaded, and
// designing its walls once per worker instead of once per run keeps the study's time in the runs.
class DevicePool {
 public:
  DevicePool(const TauProduct& product, const StudyDesigns& designs) : product_(product), designs_(designs) {}
  std::unique_ptr<WorkerDevices> take() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!free_.empty()) {
        std::unique_ptr<WorkerDevices> devices = std::move(free_.back());
        free_.pop_back();
        return devices;
      }
    }
    return std::make_unique<WorkerDevices>(product_, designs_);
  }
  void give(std::unique_ptr<WorkerDevices> devices) {
    std::lock_guard<std::mutex> lock(mutex_);
    free_.push_back(std::move(devices));
  }

 private:
  const TauProduct& product_;
  const StudyDesigns& designs_;
  std::mutex mutex_;
  std::vector<std::unique_ptr<WorkerDevices>> free_;
};

// The q-quantile of values (nearest rank); infinite values sort last.
double quantile(std::vector<double> values, double q) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const auto rank = static_cast<std::size_t>(std::ceil(q * static_cast<double>(values.size())));
  return values[std::min(values.size() - 1, rank > 0 ? rank - 1 : 0)];
}
}  // namespace

GridStudy runGrid(const TauModel& model, const TauProduct& product, const StudyDesigns& designs,
                  const GridOptions& options, const std::function<void()>& job_done) {
  const auto& variants = studyVariants();
  const int grid = options.grid, runs = options.runs;
  if (grid < 2 || runs < 1) throw Error("study: the grid needs at least 2 points per side and 1 run");
  const double half = model.workspaceHalfSide();
  auto coordinate = [&](std::size_t i) { return -half + 2.0 * half * static_cast<double>(i) / (grid - 1); };
  const std::size_t points = static_cast<std::size_t>(grid * grid);
  const std::size_t jobs = points * static_cast<std::size_t>(runs);
  std::vector<RunMetrics> results(jobs * kNumVariants);
  DevicePool pool(product, designs);
  experiments::parallelFor(jobs, options.threads, [&](std::size_t job) {
    std::unique_ptr<WorkerDevices> devices = pool.take();
    const std::size_t point = job / static_cast<std::size_t>(runs);
    RunSpec spec;
    spec.x = coordinate(point % grid);
    spec.y = coordinate(point / grid);
    spec.seed = runSeed(options.seed, job);
    for (std::size_t v = 0; v < kNumVariants; ++v) {
      spec.controller = variants[v].controller;
      spec.scenario = variants[v].scenario;
      spec.max_delay_samples = variants[v].delay;
      spec.quantize = options.quantize;
      spec.applied_command_reported = options.applied_command_reported;
      spec.substeps = options.substeps;
      spec.relinearize_tolerance = options.relinearize_tolerance;
      StudyDevice& device = variants[v].delay > 0 ? devices->delayed : devices->undelayed;
      results[job * kNumVariants + v] = simulateRun(model, device, spec);
    }
    pool.give(std::move(devices));
    if (job_done) job_done();
  });

  GridStudy study;
  study.grid = grid;
  study.runs = runs;
  study.simulated_runs = results.size();
  study.lowest_k_z1.fill(std::numeric_limits<double>::infinity());
  study.lowest_k_zs.fill(std::numeric_limits<double>::infinity());
  std::vector<double> delay_depths;
  for (std::size_t p = 0; p < points; ++p) {
    GridPoint& point = study.points.emplace_back();
    point.x = coordinate(p % grid);
    point.y = coordinate(p / grid);
    for (std::size_t v = 0; v < kNumVariants; ++v) {
      std::vector<double> dz1, kz1, dzs, kzs, pen;
      for (int r = 0; r < runs; ++r) {
        const RunMetrics& m = results[(p * runs + r) * kNumVariants + v];
        const bool lost = m.fault != Fault::kNone;
        study.faults += lost;
        study.variant_faults[v] += lost;
        if (variants[v].delay > 0) {
          ++study.delay_runs;
          study.delay_runs_over_1mm += m.max_penetration > 1e-3 || lost;
          delay_depths.push_back(lost ? std::numeric_limits<double>::infinity() : m.max_penetration);
        }
        study.referee_max_penetration[v] =
            std::max(study.referee_max_penetration[v], 1e-3 * m.referee.max_true_penetration_mm);
        study.referee_max_energy[v] = std::max(study.referee_max_energy[v], m.referee.generated_energy_mJ);
        dz1.push_back(m.d_z1);
        kz1.push_back(m.k_z1);
        dzs.push_back(m.d_zs);
        kzs.push_back(m.k_zs);
        pen.push_back(m.max_penetration);
      }
      PointStatistics& s = point.variants[v];
      s = {statistics(dz1), statistics(kz1), statistics(dzs), statistics(kzs), statistics(pen)};
      study.lowest_k_z1[v] = std::min(study.lowest_k_z1[v], s.k_z1.mean);
      study.lowest_k_zs[v] = std::min(study.lowest_k_zs[v], s.k_zs.mean);
      study.highest_k_z1[v] = std::max(study.highest_k_z1[v], s.k_z1.mean);
      study.highest_k_zs[v] = std::max(study.highest_k_zs[v], s.k_zs.mean);
      study.max_penetration[v] = std::max(study.max_penetration[v], s.penetration.max);
    }
  }
  study.delay_max_of_90_quantile = quantile(delay_depths, 1.0 - 1.0 / 91.0);
  return study;
}

CentreTraces centreTraces(const TauModel& model, const TauProduct& product, const TauPolicy::WallDesign& design,
                          Scenario scenario, std::uint64_t base_seed) {
  CentreTraces traces;
  StudyDevice device(product, design, 0);
  RunSpec spec;
  spec.scenario = scenario;
  spec.seed = runSeed(base_seed, 0);
  spec.controller = Controller::kLqr;
  simulateRun(model, device, spec, {}, &traces.lqr);
  spec.controller = Controller::kSpring;
  simulateRun(model, device, spec, {}, &traces.spring);
  return traces;
}

experiments::ReproductionTable reproductionTable(const TauModel& model, const LqrWallDesign& design,
                                                 const Requirements& requirements, const GridStudy& study) {
  using experiments::Accepted;
  experiments::ReproductionTable table;
  // Variants: 0 lqr_s1, 1 spring_s1, 2 lqr_s2, 3 spring_s2, 4 lqr_s1_delay, 5 lqr_s2_delay.
  const double lqr_kz1_low = study.lowest_k_z1[0], spring_kz1_high = study.highest_k_z1[1];
  const double lqr_kzs1_low = study.lowest_k_zs[0], spring_kzs1_high = study.highest_k_zs[1];
  const double lqr_kzs2_low = study.lowest_k_zs[2], spring_kzs2_high = study.highest_k_zs[3];
  table.add({"001", "fastest closed-loop pole", 2480.0, design.report.fastest_pole_rad_s, "within 10 %", false,
             "rad/s", {}, Accepted::within(2480.0, 248.0)});
  table.add({"001", "sc.1 lowest K_z1, LQR", 17174.0, lqr_kz1_low, ">= 3x highest spring K_z1 (paper 5.5x)", false,
             "N/m", {}, Accepted::atLeast(3.0 * spring_kz1_high)});
  table.add({"001", "sc.1 highest K_z1, spring", 3112.6, spring_kz1_high, "within 30 % (device mass differs)",
             false, "N/m", {}, Accepted::within(3112.6, 0.3 * 3112.6)});
  table.add({"001", "sc.1 lowest K_zs, LQR", 92387.0, lqr_kzs1_low, ">= 10x highest spring K_zs (paper 15x)",
             false, "N/m", {}, Accepted::atLeast(10.0 * spring_kzs1_high)});
  table.add({"001", "sc.1 highest K_zs, spring", 6180.5, spring_kzs1_high, "within 15 % of 6000 N/m design",
             false, "N/m", {}, Accepted::within(6180.5, 0.15 * 6180.5)});
  table.add({"001", "sc.2 lowest K_zs, LQR", 65002.0, lqr_kzs2_low, ">= 10x highest spring K_zs (paper 10x)",
             false, "N/m", {}, Accepted::atLeast(10.0 * spring_kzs2_high)});
  table.add({"001", "sc.2 highest K_zs, spring", 6202.1, spring_kzs2_high, "within 15 %", false, "N/m", {},
             Accepted::within(6202.1, 0.15 * 6202.1)});
  const double lqr_pen = std::max(study.max_penetration[0], study.max_penetration[2]);
  table.addBound("001", "max penetration, LQR", 1e3 * lqr_pen, "< 1 mm", Accepted::below(1.0), "mm");
  // The same claim judged by the referee from the plant's truth (depth from the entry point it reads off
  // the scene's force, whichever renderer held the tool), with the spring baseline beside it.
  const double referee_lqr = 1e3 * std::max(study.referee_max_penetration[0], study.referee_max_penetration[2]);
  const double referee_spring = 1e3 * std::max(study.referee_max_penetration[1], study.referee_max_penetration[3]);
  char referee_criterion[80];
  std::snprintf(referee_criterion, sizeof referee_criterion, "< 1 mm and <= half the spring's (%.3g mm)",
                referee_spring);
  table.addBound("001", "referee: max true penetration, LQR vs spring", referee_lqr, referee_criterion,
                 Accepted::below(std::min(1.0, 0.5 * referee_spring)), "mm");
  // Paper 001's CoS-D: the deepest of 90 runs below 1.1 mm. Over our many more runs the maximum is a
  // rarer event than the paper measured; its like is the quantile the deepest of 90 runs falls at.
  table.addBound("001", "penetration, LQR, delay 0-3, quantile 1-1/91 (deepest of 90 runs)",
                 1e3 * study.delay_max_of_90_quantile, "< 1.1 mm (paper CoS-D: max of 90 runs)", Accepted::below(1.1),
                 "mm");
  // Paper 001's CoS-D: 3 of its 90 runs (scenario 1) above 1 mm.
  const double delay_over_share =
      100.0 * static_cast<double>(study.delay_runs_over_1mm) / static_cast<double>(study.delay_runs);
  table.addBound("001", "runs above 1 mm, LQR, delay 0-3", delay_over_share, "<= 3.3 % (paper CoS-D: 3 of 90)",
                 Accepted::atMost(100.0 * 3.0 / 90.0), "%");
  const StepResponse& step = requirements.step;
  table.addBound("001", "step reference overshoot", step.overshoot_percent, "< 2 %", Accepted::below(2.0), "%");
  table.addBound("001", "step reference rise time", step.rise_time, "< 0.05 s", Accepted::below(0.05), "s");
  table.addBound("001", "step reference settling time", step.settling_time, "< 0.1 s", Accepted::below(0.1), "s");
  table.addBound("001", "15 N force step, max joint deviation", requirements.deviation, "< 0.001 rad",
                 Accepted::below(1e-3), "rad");
  // The device senses the joints to one encoder count (0.0015 rad), coarser than the paper's
  // 0.001 rad bound, so the loop it runs is held to the bound plus one count of sensing error.
  const double encoder_bound = 1e-3 + model.encoderResolution();
  char criterion[64];
  std::snprintf(criterion, sizeof criterion, "< 0.001 rad + 1 count (%.4f rad)", encoder_bound);
  table.addBound("001", "15 N force step, observer on the encoders", requirements.deviation_encoders, criterion,
                 Accepted::below(encoder_bound), "rad");
  return table;
}

}  // namespace uhaptics::study
