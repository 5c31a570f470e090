#include "uhaptics/experiments/exo_fig4.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "uhaptics/backends/exo_finger_plant.hpp"
#include "uhaptics/backends/referee.hpp"
#include "uhaptics/renderers/exo_finger_policy.hpp"
#include "uhaptics/renderers/underactuated_renderers.hpp"
#include "zwidth_common.hpp"  // HardwarePath: the board's sensing and command delay

namespace uhaptics::exo {
namespace {

constexpr double kFig4Margin = 0.05;  // FingerTrajectory::synthesized's default: off the range limits

FingerTrajectory protocolTrajectory(const ExoFingerModel& model, const Fig4Options& o) {
  if (!o.trajectory_csv.empty()) return FingerTrajectory::fromCsv(model, o.trajectory_csv);
  return o.contact ? FingerTrajectory::synthesizedAround(model, o.proxy, o.contact_amplitude, o.duration_s, o.period_s,
                                                         1000.0)
                   : FingerTrajectory::synthesized(model, o.duration_s, o.period_s, 1000.0, kFig4Margin);
}

/// Fig4EnergyOptions::loop: the Fig. 4 motion's ranges and margin, both joints at one period, the
/// PIP a quarter cycle ahead.
FingerTrajectory loopTrajectory(const ExoFingerModel& model, double duration_s, double period_s) {
  if (!(duration_s > 0.0 && duration_s < 3600.0 && period_s > 0.05 && period_s < 600.0))
    throw Error("exo Fig. 4 loop: duration must lie in (0, 3600) s, period in (0.05, 600) s");
  constexpr double kRate = 1000.0;
  const auto n = static_cast<std::size_t>(std::ceil(duration_s * kRate)) + 1;
  std::vector<double> t(n);
  std::vector<ExoFingerModel::TaskVector> x(n);
  const ExoFingerModel::TaskVector lo = model.taskLower(), span = model.taskUpper() - model.taskLower();
  for (std::size_t i = 0; i < n; ++i) {
    t[i] = static_cast<double>(i) / kRate;
    const double phase = 2.0 * M_PI * t[i] / period_s;
    const Vec2 unit = 0.5 * Vec2(1.0 - std::cos(phase), 1.0 - std::cos(phase + 0.5 * M_PI));
    x[i] = lo + span.cwiseProduct(Vec2::Constant(kFig4Margin) + (1.0 - 2.0 * kFig4Margin) * unit);
  }
  return FingerTrajectory::fromSamples(model, std::move(t), std::move(x), "Fig. 4 loop");
}

/// The device states the simulation steps through at the host rate, and avg(|J_a|) over them (the
/// paper's normalization).
struct ProtocolFrames {
  std::vector<double> times;
  std::vector<ExoFingerModel::JointVector> states;
  double avg_abs_Ja = 0.0;
};

ProtocolFrames protocolFrames(const ExoFingerModel& model, const FingerTrajectory& trajectory, double rate_hz) {
  ExoFingerSim sim(model, trajectory, {rate_hz, true});
  ProtocolFrames f;
  double sum_Ja = 0.0;
  while (true) {
    const auto& s = sim.state();
    f.times.push_back(s.time);
    f.states.push_back(s.q);
    ExoFingerModel::Jacobian J;
    model.jacobian(s.q, J);
    sum_Ja += J.col(0).norm();
    if (sim.finished()) break;
    sim.step();
  }
  f.avg_abs_Ja = sum_Ja / static_cast<double>(f.states.size());
  return f;
}

}  // namespace

const char* methodName(int m) {
  static constexpr const char* kNames[] = {"standard", "null-space", "subspace (linearized)", "subspace (nonlinear)"};
  return m >= 0 && m < kMethodCount ? kNames[m] : "?";
}
const char* methodKey(int m) {
  static constexpr const char* kKeys[] = {"standard", "nullspace", "subspace_lin", "subspace_nl"};
  return m >= 0 && m < kMethodCount ? kKeys[m] : "?";
}

Fig4Result runFig4(const ExoFingerModel& model, const Fig4Options& o) {
  if (!(o.zq > 0.0 && std::isfinite(o.zq))) throw Error("Z_q must be positive");
  if (!(o.min_actuator_step > 0.0)) throw Error("min_actuator_step must be positive");
  const ProtocolFrames frames = protocolFrames(model, protocolTrajectory(model, o), o.update_rate_hz);
  const std::vector<double>& times = frames.times;
  const std::vector<ExoFingerModel::JointVector>& states = frames.states;
  Fig4Result r;
  r.avg_abs_Ja = frames.avg_abs_Ja;
  r.zx = o.zq / (r.avg_abs_Ja * r.avg_abs_Ja);

  UnderactuatedGains<ExoFingerModel> gains;
  gains.Zx = r.zx * Mat2::Identity();
  gains.Zq(0, 0) = o.zq;
  gains.force_limit = model.effortLimits();
  StandardRenderer<ExoFingerModel> standard(model, gains);
  NullSpaceRenderer<ExoFingerModel> nullspace(model, gains);
  LinearizedSubspaceRenderer<ExoFingerModel> linearized(model, gains);
  NonlinearSubspaceRenderer<ExoFingerModel> nonlinear(model, gains, o.solver);

  const ExoFingerModel::TaskVector proxy = o.contact ? o.proxy : ExoFingerModel::TaskVector::Zero();
  r.frames.resize(states.size());
  long iteration_sum = 0;
  for (std::size_t k = 0; k < states.size(); ++k) {
    Fig4Frame& f = r.frames[k];
    f.t = times[k];
    f.q = states[k];
    model.forward(f.q, f.x);
    const auto tickOne = [&](auto& renderer, int m) {
      ExoFingerModel::ActuatorVector tau;
      f.fault[m] = static_cast<int>(renderer.tick(f.q, proxy, tau));
      f.force[m] = tau(0);
      f.theory[m] = renderer.displayedImpedance()(0, 0);  // S = (1, 0): the actuated block
    };
    tickOne(standard, kStandard);
    tickOne(nullspace, kNullSpace);
    tickOne(linearized, kSubspaceLinearized);
    tickOne(nonlinear, kSubspaceNonlinear);
    f.nonlinear_iterations = nonlinear.last().nonlinear.iterations;
    f.nonlinear_residual = nonlinear.last().nonlinear.residual;
    iteration_sum += f.nonlinear_iterations;
    r.max_nonlinear_iterations = std::max(r.max_nonlinear_iterations, f.nonlinear_iterations);
    if (std::isfinite(f.nonlinear_residual)) r.max_nonlinear_residual = std::max(r.max_nonlinear_residual, f.nonlinear_residual);
    for (int m = 0; m < kMethodCount; ++m) {
      f.fd[m] = std::numeric_limits<double>::quiet_NaN();
      if (k > 0) {
        const Fig4Frame& prev = r.frames[k - 1];
        f.fd[m] = underactuated::finiteDifferenceStiffness<1>(Vec<1>(f.force[m] - prev.force[m]),
                                                              Vec<1>(f.q(0) - prev.q(0)), o.min_actuator_step);
      }
    }
  }
  r.mean_nonlinear_iterations = static_cast<double>(iteration_sum) / static_cast<double>(states.size());

  for (int m = 0; m < kMethodCount; ++m) {
    Fig4MethodSummary& s = r.summary[m];
    s.theory_min = std::numeric_limits<double>::infinity();
    s.theory_max = -std::numeric_limits<double>::infinity();
    s.fd_max = -std::numeric_limits<double>::infinity();
    for (const Fig4Frame& f : r.frames) {
      ++s.frames;
      if (f.fault[m] != 0) ++s.faults;
      s.max_abs_force = std::max(s.max_abs_force, std::abs(f.force[m]));
      s.theory_min = std::min(s.theory_min, f.theory[m]);
      s.theory_max = std::max(s.theory_max, f.theory[m]);
      // Passive in theory: d tau_a / d q_a <= 0 (tiny positive round-off counts as passive).
      if (f.theory[m] <= 1e-12 * o.zq) ++s.theory_passive;
      if (std::isfinite(f.fd[m])) {
        ++s.fd_frames;
        if (f.fd[m] <= 0.0) ++s.fd_passive;
        s.fd_max = std::max(s.fd_max, f.fd[m]);
      }
      if (m == kSubspaceLinearized || m == kSubspaceNonlinear)
        r.max_subspace_theory_error = std::max(r.max_subspace_theory_error, std::abs(f.theory[m] + o.zq));
    }
  }
  return r;
}

double heldForceDelay(double servo_period, int command_delay, double board_period, double force_loop_tau) noexcept {
  if (!(force_loop_tau > 0.0)) return (command_delay + 0.5) * servo_period;
  // A command from the reading at t_k - d T is held over the T / h board steps ending at t_k + h ..
  // t_k + T: smoothed, it trails its reading by d T + (T + h) / 2. A first-order lag stepped at h
  // (y += a (u - y), a = 1 - e^(-h/tau)) trails a smooth input by (1 - a) / a steps, h / (e^(h/tau) - 1).
  // The referee sets the force at the period's end, t_k + T, against the period's motion, centred
  // at t_k + T / 2: T / 2 earlier.
  const double lag = board_period / std::expm1(board_period / force_loop_tau);
  return command_delay * servo_period + 0.5 * board_period + lag;
}

namespace {

using experiments::zwidth_detail::Channels;
using experiments::zwidth_detail::HardwarePath;

ExoFingerPolicy::Method policyMethod(int m) {
  switch (m) {
    case kStandard: return ExoFingerPolicy::Method::kStandard;
    case kNullSpace: return ExoFingerPolicy::Method::kNullSpace;
    case kSubspaceNonlinear: return ExoFingerPolicy::Method::kSubspaceProxy;
    default: throw Error(std::string("exo Fig. 4 energy: the device's policy does not render ") + methodName(m));
  }
}

/// One run: the policy (its method and Z_x set) drives the plant along `path` through the hardware
/// path; the scene holds the proxy at x = 0 from the sensed finger angles.
Fig4EnergyRun runPolicy(const ExoFingerModel& model, FingerTrajectory path, ExoFingerPolicy& policy,
                        const BoardSpec& spec, double servo_period, double plant_period, int delay, bool lag) {
  const long ticks = std::lround(path.duration() / servo_period);
  auto channel = std::make_shared<RefereeChannel>();
  RefereedPlant plant(std::make_unique<ExoFingerBoardPlant>(std::make_unique<const ExoFingerModel>(model),
                                                            std::move(path), ExoFingerSimOptions{1.0 / plant_period, lag}),
                      channel);
  HardwarePath hardware(spec, servo_period, delay);
  policy.reset(delay);
  Fig4EnergyRun run;
  SensedState state;
  double previous_force = 0.0, previous_length = 0.0;
  for (long k = 0; k < ticks; ++k) {
    Channels efforts{};
    bool ok = hardware.read(plant);
    if (ok) {
      const bool first = k == 0;
      policy.sense(SensedJoints{hardware.q().data(), hardware.rates().data(), first}, state);
      policy.setFingerJointTorque(-policy.couplingStiffness() * policy.data().x);  // Z_x (x_p - x), x_p = 0
      SceneInput input;
      input.dt = servo_period;
      input.time = static_cast<double>(k) * servo_period;
      input.seen_position = state.position;
      ok = policy.render(input, efforts.data()) == Fault::kNone && std::isfinite(efforts[0]);
      plant.setSceneForce(policy.sceneForceAtUserPort(input.force));
      const double length = hardware.q()[0];
      if (ok && k > 0) run.stiffening_W -= (efforts[0] - previous_force) * (length - previous_length) / servo_period;
      previous_force = ok ? efforts[0] : 0.0;
      previous_length = length;
    }
    if (!ok) {
      ++run.faults;
      efforts.fill(0.0);
    }
    run.max_abs_force_N = std::max(run.max_abs_force_N, std::abs(efforts[0]));
    const Channels applied = hardware.command(efforts);
    plant.applyCommand(applied.data());
    plant.advance(servo_period);
  }
  run.generated_mJ = channel->latest().generated_energy_mJ;
  return run;
}

}  // namespace

Fig4Energy runFig4Energy(const ExoFingerModel& model, const Fig4Options& o, const Fig4EnergyOptions& e) {
  if (!(o.zq > 0.0 && std::isfinite(o.zq))) throw Error("Z_q must be positive");
  if (!e.make_policy) throw Error("exo Fig. 4 energy: no policy factory");
  if (!(e.servo_period_s > 0.0 && e.board_period_s > 0.0 && e.fine_period_s > 0.0) ||
      e.board_period_s > e.servo_period_s || e.fine_period_s > e.servo_period_s)
    throw Error("exo Fig. 4 energy: periods must be > 0, the board's and the fine one at most the servo period");
  if (e.command_delay < 0 || e.command_delay > experiments::kMaxZWidthDelay)
    throw Error("exo Fig. 4 energy: command_delay must lie in 0.." + std::to_string(experiments::kMaxZWidthDelay));
  const FingerTrajectory trajectory = !o.trajectory_csv.empty() ? FingerTrajectory::fromCsv(model, o.trajectory_csv)
                                      : e.loop ? loopTrajectory(model, o.duration_s, o.period_s)
                                               : FingerTrajectory::synthesized(model, o.duration_s, o.period_s, 1000.0,
                                                                               kFig4Margin);
  const ProtocolFrames frames = protocolFrames(model, trajectory, o.update_rate_hz);

  // The path both ways, on the same 1 kHz knots (the synthesized motion's own).
  constexpr double kKnotRate = 1000.0;
  const long knots = std::lround(trajectory.duration() * kKnotRate);
  std::vector<double> time(static_cast<std::size_t>(knots) + 1);
  std::vector<ExoFingerModel::TaskVector> forward(time.size()), backward(time.size());
  for (std::size_t i = 0; i < time.size(); ++i) {
    time[i] = static_cast<double>(i) / kKnotRate;
    forward[i] = trajectory.at(trajectory.startTime() + time[i]);
  }
  std::reverse_copy(forward.begin(), forward.end(), backward.begin());

  Fig4Energy result;
  result.options = e;
  result.closure_rad = (forward.back() - forward.front()).norm();
  std::unique_ptr<DevicePolicy> made = e.make_policy();
  auto* policy = dynamic_cast<ExoFingerPolicy*>(made.get());
  if (policy == nullptr) throw Error("exo Fig. 4 energy: the factory did not make the exoskeleton's policy");
  policy->setCouplingStiffness(o.zq / (frames.avg_abs_Ja * frames.avg_abs_Ja));
  result.zx = policy->couplingStiffness();
  result.zq = policy->actuatorStiffness();
  result.delay_s = heldForceDelay(e.servo_period_s, e.command_delay, e.board_period_s,
                                  e.force_loop_lag ? model.forceLoopTimeConstant() : 0.0);
  const auto path = [&](const std::vector<ExoFingerModel::TaskVector>& x) {
    return FingerTrajectory::fromSamples(model, time, x, "Fig. 4 motion");
  };
  for (int m : kPolicyMethods) {
    policy->setMethod(policyMethod(m));
    Fig4MethodEnergy& r = result.methods[static_cast<std::size_t>(m)];
    const auto product = [&](const std::vector<ExoFingerModel::TaskVector>& x) {
      return runPolicy(model, path(x), *policy, e.spec, e.servo_period_s, e.board_period_s, e.command_delay,
                       e.force_loop_lag);
    };
    const auto fine = [&](const std::vector<ExoFingerModel::TaskVector>& x) {
      return runPolicy(model, path(x), *policy, e.spec, e.fine_period_s, e.fine_period_s, 0, false);
    };
    r.forward = product(forward);
    r.backward = product(backward);
    r.fine_forward = fine(forward);
    r.fine_backward = fine(backward);
  }
  return result;
}

Fig4Study runFig4Study(const ExoFingerModel& model, const Fig4Options& options, double contact_amplitude_deg) {
  Fig4Study study;
  study.options = options;
  study.contact_amplitude_deg = contact_amplitude_deg;
  study.protocol = runFig4(model, options);
  Fig4Options contact = options;
  contact.contact = true;
  contact.proxy = ExoFingerModel::TaskVector(45.0, 50.0) * (M_PI / 180.0);
  contact.contact_amplitude = contact_amplitude_deg * M_PI / 180.0;
  contact.trajectory_csv.clear();
  study.contact = runFig4(model, contact);
  return study;
}

namespace {

void addEnergyRows(experiments::ReproductionTable& table, const Fig4Energy& e) {
  using experiments::Accepted;
  const auto mJ = [](double v) {
    char text[32];
    std::snprintf(text, sizeof text, "%.3g mJ", v);
    return std::string(text);
  };
  const auto& sub = e.methods[kSubspaceNonlinear];
  const auto& std_ = e.methods[kStandard];
  const auto& ns = e.methods[kNullSpace];
  // The sampled hold's share in closed form (delta S, first order in delta) is met within 1.1 % by
  // every run (docs/exo-finger.md); 5 % leaves room for the second-order terms, (omega delta)^2
  // about 0.4 % at this motion's 1 Hz content and 7 ms, and the force loop's smoothing of the steps.
  constexpr double kHoldTolerance = 0.05;
  const double sub_hold = sub.holdClosedForm_mJ(e.delay_s), std_hold = std_.holdClosedForm_mJ(e.delay_s);
  const double ns_hold = ns.holdClosedForm_mJ(e.delay_s);
  const std::string policy = " (device policy, hardware path, referee)";
  if (!e.options.loop) {
    table.addBound("000", "subspace" + policy + ", Fig. 4 motion: energy given to the finger (issue 39: <= 0)",
                   sub.forward.generated_mJ, "<= the sampled hold's delta S = " + mJ(sub_hold) + " + 5 %",
                   Accepted::atMost((1.0 + kHoldTolerance) * sub_hold), "mJ");
    table.addBound("000", "standard" + policy + ", Fig. 4 motion: energy given to the finger (issue 39: > 0)",
                   std_.forward.generated_mJ, "> 0", Accepted::above(0.0), "mJ");
    // The motion's path back retraces its path out: no field does net work on it, and the
    // standard method's positive energy is its sampled hold's (delta S), as the subspace proxy's is.
    table.addBound("000", "standard, Fig. 4 motion: its field's own work (the path back retraces the path out)",
                   std_.fieldWork_mJ(), "|W| <= 1 % of delta S = " + mJ(std_hold),
                   Accepted::within(0.0, 0.01 * std_hold), "mJ");
    return;
  }
  table.addBound("000", "subspace, loop either way: its field's own work (a spring in l_x)", sub.fieldWork_mJ(),
                 "|W| <= 1 % of delta S = " + mJ(sub_hold), Accepted::within(0.0, 0.01 * sub_hold), "mJ");
  table.addBound("000", "subspace" + policy + ", loop, PIP a quarter cycle behind: energy given to the finger",
                 sub.backward.generated_mJ, "<= the sampled hold's delta S = " + mJ(sub_hold) + " + 5 %",
                 Accepted::atMost((1.0 + kHoldTolerance) * sub_hold), "mJ");
  table.addBound("000", "standard" + policy + ", loop, PIP a quarter cycle behind: energy beyond the sampled hold",
                 std_.backward.generated_mJ - std_hold, "> 5 % of delta S = " + mJ(std_hold),
                 Accepted::above(kHoldTolerance * std_hold), "mJ");
  table.addBound("000", "null-space" + policy + ", loop, PIP a quarter cycle behind: energy beyond the sampled hold",
                 ns.backward.generated_mJ - ns_hold, "> 5 % of delta S = " + mJ(ns_hold),
                 Accepted::above(kHoldTolerance * ns_hold), "mJ");
}

}  // namespace

experiments::ReproductionTable reproductionTable(const Fig4Study& study, const Fig4Energy* fig4_motion,
                                                 const Fig4Energy* loop) {
  experiments::ReproductionTable table;
  const Fig4Result& r = study.protocol;
  const Fig4Result& rc = study.contact;
  const double zq = study.options.zq;
  const auto& nl = r.summary[kSubspaceNonlinear];
  const auto& lin = r.summary[kSubspaceLinearized];
  table.addWithin("000", "subspace d tau_a/d q_a in theory = -Z_q (eq. 9), worst frame", -zq,
                  -zq - r.max_subspace_theory_error, 1e-9 * zq, "N/m");
  table.addWithin("000", "subspace passive in theory, share of frames", 100.0,
                  100.0 * std::min(nl.theoryShare(), lin.theoryShare()), 0.0, "%");
  table.addWithin("000", "subspace (eq. 6, nonlinear) passive by finite differences", 100.0, 100.0 * nl.fdShare(), 0.0,
                  "%");
  for (int m : {kStandard, kNullSpace}) {
    const auto& s = r.summary[m];
    table.addWithin("000", std::string(methodName(m)) + " passive in theory (Z_x = k I), share of frames", 100.0,
                    100.0 * s.theoryShare(), 0.0, "%");
    table.addBound("000", std::string(methodName(m)) + " passive by finite differences (paper: not always)",
                   100.0 * s.fdShare(), "< 100", experiments::Accepted::below(100.0), "%");
  }
  // The linearized form (eq. 8) is checked where its linearization is meant to hold (the contact
  // variant) and only reported for the Fig. 4 protocol: there the proxy is up to 95 deg from the
  // finger (the paper's own caveat on the linearization), and the share depends on our assumed
  // linkage. The exact form, eq. 6, is checked in both.
  const auto& lin_contact = rc.summary[kSubspaceLinearized];
  table.addWithin("000", "subspace (eq. 8, linearized) passive by finite differences, finger within " +
                             std::to_string(static_cast<int>(std::lround(study.contact_amplitude_deg))) +
                             " deg of the proxy",
                  100.0, 100.0 * lin_contact.fdShare(), 0.0, "%");
  table.addWithin("000", "subspace (eq. 6, nonlinear) passive by finite differences, contact variant", 100.0,
                  100.0 * rc.summary[kSubspaceNonlinear].fdShare(), 0.0, "%");
  if (fig4_motion != nullptr) addEnergyRows(table, *fig4_motion);
  if (loop != nullptr) addEnergyRows(table, *loop);
  return table;
}

}  // namespace uhaptics::exo
