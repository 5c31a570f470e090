// uhaptics-rhi-experiments: paper 003 on the simulated 4-DoF redundant haptic interface and the
// 3-DoF example arm. Writes CSV + PNG per study, summary.txt and reproduction.csv into --out.
// Exit status 0 when the experiments ran (pass/fail per check is in reproduction.csv), 2 on error.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "uhaptics/experiments/reproduction.hpp"
#include "uhaptics/experiments/rhi_experiments.hpp"
#include "uhaptics/tools/csv.hpp"
#include "uhaptics/tools/plot.hpp"

using namespace uhaptics;
using uhaptics::tools::CsvWriter;

namespace {

void writeExample(const rhi::ExampleResult& ex, const Planar3Model& model, const std::string& dir) {
  CsvWriter ts(dir + "/example3_torques.csv",
               {"t", "demanded_fx", "init_tau1", "init_tau2", "init_tau3", "init_fx", "free_tau1", "free_tau2",
                "free_tau3", "free_fx", "stiff_tau1", "stiff_tau2", "stiff_tau3", "stiff_fx"});
  for (std::size_t k = 0; k < ex.samples.size(); k += 10) {
    const auto& s = ex.samples[k];
    std::vector<double> row{s.t, s.demanded_x};
    for (std::size_t c = 0; c < 3; ++c) {
      for (int i = 0; i < 3; ++i) row.push_back(s.tau[c](i));
      row.push_back(s.force_x[c]);
    }
    ts.row(row);
  }
  // Arm drawings with their FMEs (Fig. 4): joint positions and the ellipsoid matrices.
  CsvWriter cfg(dir + "/example3_configurations.csv",
                {"config", "q1", "q2", "q3", "fme_xx", "fme_xy", "fme_yy", "nu", "peak_force", "min_alpha", "x0",
                 "y0", "x1", "y1", "x2", "y2", "x3", "y3", "des_free_xx", "des_free_xy", "des_free_yy",
                 "des_stiff_xx", "des_stiff_xy", "des_stiff_yy"});
  for (const auto& c : ex.configs) {
    std::vector<double> row{c.q(0), c.q(1), c.q(2), c.fme(0, 0), c.fme(0, 1), c.fme(1, 1), c.nu, c.peak_force,
                            c.min_alpha};
    Vec2 p = model.parameters().base;
    double phi = 0.0;
    row.push_back(p(0));
    row.push_back(p(1));
    for (int i = 0; i < 3; ++i) {
      phi += c.q(i);
      p += 0.25 * Vec2(std::cos(phi), std::sin(phi));
      row.push_back(p(0));
      row.push_back(p(1));
    }
    for (const Mat2* m : {&ex.free_fme, &ex.stiff_fme}) {
      row.push_back((*m)(0, 0));
      row.push_back((*m)(0, 1));
      row.push_back((*m)(1, 1));
    }
    cfg.row(c.name, row);
  }
}

void writeLoop(const std::vector<rhi::LoopSample>& samples, const std::string& path, std::size_t stride = 1) {
  CsvWriter w(path, {"t", "x", "y", "force_x", "force_y", "demanded", "tau1", "tau2", "tau3", "tau4", "taun1",
                     "taun2", "taun3", "taun4", "cmd1", "cmd2", "cmd3", "cmd4", "observer", "omega", "nu", "alpha"});
  for (std::size_t k = 0; k < samples.size(); k += stride) {
    const auto& s = samples[k];
    w.row({s.t, s.x(0), s.x(1), s.force(0), s.force(1), s.demanded, s.tau(0), s.tau(1), s.tau(2), s.tau(3),
           s.tau_null(0), s.tau_null(1), s.tau_null(2), s.tau_null(3), s.tau_null_command(0), s.tau_null_command(1),
           s.tau_null_command(2), s.tau_null_command(3), s.observer, s.omega, s.nu, s.alpha});
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Paper 003: force-manipulability null-space control of a redundant planar haptic interface"};
  std::string out = "out/rhi-experiments";
  std::string params = UHAPTICS_PARAMS_DIR;
  bool full = false;
  int trials = 10;
  unsigned threads = 0;
  app.add_option("--out", out, "Output folder")->capture_default_str();
  app.add_option("--params", params, "Folder with rhi4.json and planar3.json")->capture_default_str();
  app.add_option("--trials", trials, "Identification pushes per ellipsoid (paper: 10)")->check(CLI::Range(2, 100));
  app.add_option("--threads", threads, "Threads for the workspace map (0 = all cores)");
  app.add_flag("--full", full, "Fine workspace grid (1 cm instead of 2.5 cm)");
  CLI11_PARSE(app, argc, argv);

  try {
    tools::ensureDirectory(out);
    const Rhi4Model model = rhi::loadRhi4(params);
    const Planar3Model arm3 = rhi::loadPlanar3(params);
    experiments::ReproductionTable table;
    std::ostringstream summary;
    summary << std::fixed << std::setprecision(3);

    // K and zeta at home.
    const rhi::Rhi4Controller controller(model, model.torqueLimits(), model.home());
    const double K = controller.majorAxis(), zeta = controller.minorAxis();
    summary << "Home ellipsoid scales (mu = 5): K = " << K << ", zeta = " << zeta << " (paper: 123, 3.3)\n";
    // The paper prints K and zeta rounded to 3 and 2 significant digits: pass within that rounding.
    table.addWithin("003", "K = mu lambda_max(M_hat_0) at home", 123.0, K, 0.5, "");
    table.addWithin("003", "zeta = lambda_min(M_hat_0) / mu at home", 3.3, zeta, 0.05, "");

    // 3-DoF example.
    const auto ex = rhi::runExample3(arm3);
    writeExample(ex, arm3, out);
    summary << "3-DoF example: K = " << ex.K << ", zeta = " << ex.zeta << " (paper: 5 x 5.8, 0.2 x 2.6)\n";
    for (const auto& c : ex.configs)
      summary << "  " << std::setw(8) << c.name << ": q = [" << c.q.transpose() << "], peak output force "
              << c.peak_force << " N of 3.5 N, min alpha " << c.min_alpha << "\n";
    table.addWithin("003", "3-DoF example: lambda_max(M_hat) at q0", 5.8, ex.K / 5.0, 0.05, "");
    table.addWithin("003", "3-DoF example: lambda_min(M_hat) at q0", 2.6, ex.zeta * 5.0, 0.05, "");
    table.addBound("003", "3-DoF example: stiff-optimized config renders F_e unsaturated",
                   ex.configs[2].peak_force, "peak = 3.5 N (alpha = 1)", ex.configs[2].min_alpha >= 1.0, "N");
    table.addBound("003", "3-DoF example: free-optimized config saturates (weaker than initial)",
                   ex.configs[1].peak_force, "free < initial < 3.5 N",
                   ex.configs[1].peak_force < ex.configs[0].peak_force && ex.configs[0].peak_force < 3.5, "N");
    tools::runPlotScript("rhi_example3.py", {out + "/example3_torques.csv", out + "/example3_configurations.csv",
                                            out + "/example3.png"});

    // Palpation: free vs stiff ellipsoid.
    const auto free_case = rhi::runPalpation(model, FmeEllipsoidMode::kFree, {}, trials);
    const auto stiff_case = rhi::runPalpation(model, FmeEllipsoidMode::kStiff, {}, trials);
    {
      CsvWriter t(out + "/palpation_table.csv",
                  {"ellipsoid", "q1", "q2", "q3", "q4", "capability_N", "peak_force_N", "inertia_model_kg",
                   "inertia_identified_kg", "friction_model_Ns_per_m", "friction_reference_Ns_per_m",
                   "friction_identified_Ns_per_m", "coulomb_model_N", "coulomb_reference_N", "coulomb_identified_N",
                   "fit_rms_N", "limit_distance_rad"});
      for (const auto* c : {&free_case, &stiff_case})
        t.row(c->name, {c->q_settled(0), c->q_settled(1), c->q_settled(2), c->q_settled(3), c->capability,
                        c->peak_force, c->inertia_model, c->inertia_identified, c->friction_model,
                        c->friction_reference, c->friction_identified, c->coulomb_model, c->coulomb_reference,
                        c->coulomb_identified, c->fit_rms,
                        c->limit_distance});
      writeLoop(free_case.push, out + "/palpation_free.csv", 5);
      writeLoop(stiff_case.push, out + "/palpation_stiff.csv", 5);
      CsvWriter id(out + "/identification.csv",
                   {"ellipsoid", "trial", "amplitude_N", "x_u", "v_u", "a_u", "force_u", "fitted_force_u"});
      for (const auto* c : {&free_case, &stiff_case})
        for (std::size_t i = 0; i < c->trials.size(); ++i)
          for (std::size_t k = 0; k < c->trials[i].samples.size(); k += 2) {
            const auto& s = c->trials[i].samples[k];
            const double fitted = c->inertia_identified * s[2] + c->friction_identified * s[1] +
                                  (s[1] > 0 ? 1.0 : -1.0) * c->coulomb_identified;
            id.row(c->name, {static_cast<double>(i), c->trials[i].push_force, s[0], s[1], s[2], s[3], fitted});
          }
    }
    const double gain = stiff_case.peak_force / free_case.peak_force - 1.0;
    summary << "Palpation at X0 = [0.5, 0.1] m along u = [0, 1], K_e = 1000 N/m:\n";
    for (const auto* c : {&free_case, &stiff_case})
      summary << "  " << std::setw(5) << c->name << " ellipsoid: q = [" << c->q_settled.transpose()
              << "], closest to a joint limit " << c->limit_distance << " rad, capability " << c->capability << " N, peak rendered force " << c->peak_force
              << " N\n      identified along u: inertia " << c->inertia_identified << " kg (model "
              << c->inertia_model << "), viscous " << c->friction_identified << " N s/m (model back-drive "
              << c->friction_reference << ", reflected without self-motion " << c->friction_model << "), Coulomb "
              << c->coulomb_identified << " N (model back-drive " << c->coulomb_reference
              << ", reflected without self-motion " << c->coulomb_model << "), fit rms " << c->fit_rms << " N\n";
    summary << "  force capability gain stiff vs free: " << 100.0 * gain << " % (paper: +51 %)\n";
    // The maximum force follows from the kinematics, the torque limits and the configuration the
    // controller settles in: 15 % of the paper's values allows for the unpublished base frame and joint
    // limits on an otherwise exact kinematic model (docs/rhi.md: why the stiff case still misses it).
    const std::string unpublished_frame =
        "the peak force follows from where the arm's base sits relative to X0 and from its joint limits, "
        "which paper 003 does not publish (docs: the RHI section); a dense scan of the self-motion "
        "manifold at X0 finds no configuration near the paper's value for any joint limit tried";
    table.addWithin("003", "Table I: max force along u, free ellipsoid", 5.674, free_case.peak_force,
                    0.15 * 5.674, "N");
    table.addWithin("003", "Table I: max force along u, stiff ellipsoid", 8.564, stiff_case.peak_force,
                    0.15 * 8.564, "N");
    table.markNeedsData(unpublished_frame);
    table.addWithin("003", "Table I: force capability gain stiff vs free", 51.0, 100.0 * gain, 15.0, "%");
    table.markNeedsData(unpublished_frame);
    table.addBound("003", "palpation stays within the (assumed) joint limits",
                   std::min(free_case.limit_distance, stiff_case.limit_distance), "closest approach > 0",
                   std::min(free_case.limit_distance, stiff_case.limit_distance) > 0.0, "rad");
    // Inertia and friction depend on the assumed masses and friction: the paper's ordering carries
    // over, the values are compared in the README only. The identifier itself is judged against the
    // model's own values at the same configuration.
    table.addBound("003", "Table I: apparent inertia free < stiff (paper 0.036 < 0.125 kg)",
                   stiff_case.inertia_identified / free_case.inertia_identified, "ratio stiff/free > 1",
                   stiff_case.inertia_identified > free_case.inertia_identified, "");
    table.addBound("003", "Table I: back-drive viscous friction free < stiff (paper 0.295 < 0.633 N s/m)",
                   stiff_case.friction_identified / free_case.friction_identified, "identified ratio stiff/free > 1",
                   free_case.friction_identified > 0.0 && stiff_case.friction_identified > free_case.friction_identified,
                   "");
    for (const auto* c : {&free_case, &stiff_case}) {
      // 15 %: the fit sees the arm's configuration change over +-2 cm and the null-space motion,
      // which the single-configuration model values leave out.
      table.addBound("003", "identified inertia matches model u^T Lambda u (" + c->name + ")", c->inertia_identified,
                     "within 15 % of " + std::to_string(c->inertia_model),
                     c->fit_valid && std::abs(c->inertia_identified / c->inertia_model - 1) < 0.15, "kg");
      // The friction reference is the model's joint friction along u at the joint velocities that
      // occurred (self-motion included), fitted with the same regressors; the reflection without
      // self-motion, u^T J#^T B J# u, assumes q_dot = J# v, which the paused self-motion breaks (README).
      table.addBound("003", "identified viscous friction matches the model's back-drive friction (" + c->name + ")",
                     c->friction_identified, "within 25 % of " + std::to_string(c->friction_reference),
                     c->fit_valid && std::abs(c->friction_identified / c->friction_reference - 1) < 0.25, "N s/m");
      table.addBound("003", "identified Coulomb friction matches the model's back-drive friction (" + c->name + ")",
                     c->coulomb_identified, "within 25 % of " + std::to_string(c->coulomb_reference),
                     c->fit_valid && std::abs(c->coulomb_identified / c->coulomb_reference - 1) < 0.25, "N");
    }
    tools::runPlotScript("rhi_palpation.py", {out, out + "/palpation.png"});

    // Workspace map.
    const double step = full ? 0.01 : 0.025;
    const auto map = rhi::workspaceRatioMap(model, step, 0.95 * model.reach(), Vec2(0.0, 1.0), threads);
    double min_ratio = INFINITY, max_ratio = 0.0;
    std::size_t valid = 0, above = 0, pinned = 0, weaker = 0, unexplained = 0, rematched = 0, lifted = 0;
    {
      CsvWriter w(out + "/workspace_ratio.csv",
                  {"kind", "x", "y", "free_force", "stiff_force", "ratio", "global_ratio", "free_cost_excess",
                   "stiff_cost_excess", "free_limit_distance", "stiff_limit_distance", "free_bound", "stiff_bound",
                   "rematched"});
      for (const auto& p : map) {
        w.row(rhi::toString(p.kind), {p.x(0), p.x(1), p.free_force, p.stiff_force, p.ratio, p.global_ratio,
                                      p.free_cost_excess, p.stiff_cost_excess, p.free_limit_distance,
                                      p.stiff_limit_distance, static_cast<double>(p.free_bound),
                                      static_cast<double>(p.stiff_bound), p.rematched ? 1.0 : 0.0});
        if (!std::isfinite(p.ratio)) continue;
        ++valid;
        above += p.ratio > 1.0 ? 1 : 0;
        pinned += p.kind == rhi::RatioKind::kPinnedAtSameStop ? 1 : 0;
        weaker += p.kind == rhi::RatioKind::kWeakerGlobalMinimum ? 1 : 0;
        unexplained += p.kind == rhi::RatioKind::kUnexplained ? 1 : 0;
        rematched += p.rematched ? 1 : 0;
        lifted += p.rematched && p.ratio > 1.0 ? 1 : 0;
        min_ratio = std::min(min_ratio, p.ratio);
        max_ratio = std::max(max_ratio, p.ratio);
      }
    }
    summary << "Workspace map (" << valid << " points, grid " << step << " m, radius <= " << 0.95 * model.reach()
            << " m): stiff/free force ratio in [" << min_ratio << ", " << max_ratio << "], > 1 at " << above
            << " of " << valid << "; ratio <= 1: " << weaker << " where the global minima are weaker (a), " << pinned
            << " with both matches at the same joint stop (b), " << unexplained << " unexplained; "
            << rematched << " points rematched from the dense scan's minima (" << lifted << " of them now > 1)\n";
    table.addBound("003", "Fig. 10: stiff/free force ratio over the workspace (minimum)", min_ratio,
                   "> 1 at >= 95 % of the grid", static_cast<double>(above) >= 0.95 * static_cast<double>(valid), "");
    // The paper's "> 1 everywhere", except where the dense scan shows the cost's global minima
    // themselves weaker (a) or both matches sit at the same joint stop (b).
    table.addBound("003", "Fig. 10: ratio > 1 wherever not explained by kinds (a), (b)",
                   static_cast<double>(unexplained), "0 unexplained points", unexplained == 0, "points");
    tools::runPlotScript("rhi_workspace.py", {out + "/workspace_ratio.csv", out + "/workspace_ratio.png"});

    // Transition with and without smoothing.
    const auto smooth = rhi::runTransition(model, true);
    const auto abrupt = rhi::runTransition(model, false);
    writeLoop(smooth.samples, out + "/transition_smooth.csv", 2);
    writeLoop(abrupt.samples, out + "/transition_abrupt.csv", 2);
    summary << "Transition (rho |M_free - M_stiff|_F = " << smooth.transition_duration
            << " s): largest null-space command step per tick " << smooth.max_null_torque_jump
            << " N m with smoothing (t = " << smooth.jump_time << " s), " << abrupt.max_null_torque_jump
            << " N m without (t = " << abrupt.jump_time << " s); applied null-space torque (after the limit scaling): "
            << smooth.max_applied_null_jump << " vs " << abrupt.max_applied_null_jump
            << " N m; joint-limit avoidance command step " << smooth.max_limit_torque_jump << " vs "
            << abrupt.max_limit_torque_jump << " N m, closest approach to a joint limit " << smooth.limit_distance
            << " vs " << abrupt.limit_distance << " rad\n";
    table.addWithin("003", "Fig. 11: transition duration rho |M_free - M_stiff|_F", 0.5,
                    smooth.transition_duration, 0.05, "s");
    table.addBound("003", "Fig. 11: null-space torque jump, smoothed vs abrupt switch",
                   smooth.max_null_torque_jump / abrupt.max_null_torque_jump, "ratio < 0.5",
                   smooth.max_null_torque_jump < 0.5 * abrupt.max_null_torque_jump, "");
    tools::runPlotScript("rhi_transition.py", {out + "/transition_smooth.csv", out + "/transition_abrupt.csv",
                                              out + "/transition.png"});

    table.writeCsv(out + "/reproduction.csv");
    std::ofstream(out + "/summary.txt") << summary.str();
    std::cout << summary.str() << "\n" << table.format() << "\n";
    // Failed checks are reported in reproduction.csv (and by uhaptics-report), not by the exit status,
    // so that one off-target number does not stop the main job's other experiments.
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "uhaptics-rhi-experiments: " << e.what() << "\n";
    return 2;
  }
}
