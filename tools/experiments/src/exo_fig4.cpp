#include "uhaptics/experiments/exo_fig4.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "uhaptics/renderers/underactuated_renderers.hpp"

namespace uhaptics::exo {

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
  FingerTrajectory trajectory =
      !o.trajectory_csv.empty()
          ? FingerTrajectory::fromCsv(model, o.trajectory_csv)
          : o.contact ? FingerTrajectory::synthesizedAround(model, o.proxy, o.contact_amplitude, o.duration_s,
                                                            o.period_s, 1000.0)
                      : FingerTrajectory::synthesized(model, o.duration_s, o.period_s, 1000.0);
  ExoFingerSim sim(model, trajectory, {o.update_rate_hz, true});

  // Pass 1: the device states and avg(|J_a|) over the trajectory (the paper's normalization).
  std::vector<double> times;
  std::vector<ExoFingerModel::JointVector> states;
  double sum_Ja = 0.0;
  while (true) {
    const auto& s = sim.state();
    times.push_back(s.time);
    states.push_back(s.q);
    ExoFingerModel::Jacobian J;
    model.jacobian(s.q, J);
    sum_Ja += J.col(0).norm();
    if (sim.finished()) break;
    sim.step();
  }
  Fig4Result r;
  r.avg_abs_Ja = sum_Ja / static_cast<double>(states.size());
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

experiments::ReproductionTable reproductionTable(const Fig4Study& study) {
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
  return table;
}

}  // namespace uhaptics::exo
