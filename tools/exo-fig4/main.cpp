// uhaptics-exo-fig4: paper 000's Fig. 4 on the simulated finger exoskeleton.
//
// A finger trajectory is played on the simulated device at the host rate, the proxy is held at
// x = 0, and the standard, null-space, linearized-subspace and nonlinear-subspace renderers compute
// the actuator force each frame. Then the same motion runs through the exoskeleton's own policy (its
// DevicePolicy factory, as the servo tool and CHAI3D run it) over the hardware path, each method
// forward and backward, and the referee measures the energy it gave the finger (exo_fig4.hpp).
// Written to --out: exo_fig4.csv (per frame), exo_fig4_summary.csv, exo_fig4_energy.csv, exo_fig4.png
// (joint angles, force, theoretical and finite-difference displayed impedance) and reproduction.csv
// (the paper's checkable claims next to what we measure).
#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <string>

#include "device_servo_renderers.hpp"
#include "uhaptics/backends/board_catalog.hpp"
#include "uhaptics/backends/params_location.hpp"
#include "uhaptics/experiments/exo_fig4.hpp"
#include "uhaptics/experiments/reproduction.hpp"
#include "uhaptics/experiments/zwidth.hpp"  // kMaxZWidthDelay: the hardware path's longest delay
#include "uhaptics/tools/cli.hpp"
#include "uhaptics/tools/csv.hpp"
#include "uhaptics/tools/plot.hpp"

using namespace uhaptics;

int main(int argc, char** argv) {
  CLI::App app{"Paper 000, Fig. 4: displayed impedance of four renderers on the finger exoskeleton"};
  std::string out = "out/exo-fig4";
  std::string params = defaultParamsDirectory() + "/exo_finger.json";
  std::string method = "gn";
  exo::Fig4Options o;
  app.footer(tools::CommandLine::kExitCodesHelp);
  tools::CommandLine cli(app, "uhaptics-exo-fig4");
  cli.outputFolder("--out", out, "output folder")->capture_default_str();
  cli.inputFile("--params", params, "device parameter file")->capture_default_str();
  cli.inputFile("--trajectory", o.trajectory_csv, "recorded finger trajectory (CSV: time_s,mcp_rad,pip_rad); "
                                                  "default: synthesized flexion-extension");
  cli.number("--rate", o.update_rate_hz, "host update rate, Hz (the real USB link: 500)", 10.0, 100000.0)
      ->capture_default_str();
  cli.number("--duration", o.duration_s, "synthesized trajectory length, s", 0.1, 600.0)->capture_default_str();
  cli.number("--period", o.period_s, "synthesized MCP flexion-extension period, s (PIP: 2/3 of it)", 0.1, 600.0)
      ->capture_default_str();
  // Z_q scales every force: beyond 1e6 (N/m for a normalized 1) the forces overflow nothing useful.
  cli.number("--zq", o.zq, "Z_q (paper: 1; Z_x = Z_q / avg(|J_a|)^2 I)", 1e-6, 1e6)->capture_default_str();
  cli.number("--min-step", o.min_actuator_step, "smallest actuator motion (m) that defines a "
                                                "finite-difference impedance", 1e-12, 1e-2)->capture_default_str();
  cli.number("--tolerance", o.solver.tolerance, "nonlinear solve tolerance, rad", 1e-15, 1e-2)->capture_default_str();
  cli.integer("--max-iterations", o.solver.max_iterations, "nonlinear solve iteration cap", 1, 1000)
      ->capture_default_str();
  cli.choice("--solver", method, "nonlinear solver: gn (Gauss-Newton) or lm (Levenberg-Marquardt)", {"gn", "lm"})
      ->capture_default_str();
  double contact_deg = 5.0;
  cli.number("--contact-amplitude", contact_deg, "contact variant: finger within +- this many deg of a "
                                                 "proxy held at MCP 45, PIP 50 deg", 0.5, 40.0)
      ->capture_default_str();
  int command_delay = ServoLoop::kCommandDelayPeriods;
  cli.integer("--command-delay", command_delay, "energy runs: periods between a reading and its command "
                                                "(the board protocol: 1)", 0, experiments::kMaxZWidthDelay)
      ->capture_default_str();
  int force_loop_lag = 1;
  cli.integer("--force-loop-lag", force_loop_lag, "energy runs: the board's force loop lags (1) or not (0)", 0, 1)
      ->capture_default_str();
  if (const int status = cli.parse(argc, argv); status >= 0) return status;
  o.solver.method = method == "lm" ? LeastSquaresMethod::kLevenbergMarquardt : LeastSquaresMethod::kGaussNewton;

  try {
    const ExoFingerModel model = ExoFingerModel::load(params);
    const exo::Fig4Study study = exo::runFig4Study(model, o, contact_deg);
    // The device's policy from its factory, on this parameter file.
    DeviceDefinition device = findDevice("exo");
    const std::filesystem::path params_path(params);
    device.params_file = params_path.filename().string();
    const std::string params_dir = params_path.parent_path().empty() ? "." : params_path.parent_path().string();
    exo::Fig4EnergyOptions energy_options;
    energy_options.spec = boardSpecFromFile(device, params);
    energy_options.servo_period_s = 1.0 / energy_options.spec.servo_rate_hz;
    energy_options.board_period_s = 1.0 / energy_options.spec.sample_rate_hz;
    energy_options.command_delay = command_delay;
    energy_options.force_loop_lag = force_loop_lag != 0;
    energy_options.make_policy = [&] { return makeDevicePolicy(device, params_dir); };
    const exo::Fig4Energy energy = exo::runFig4Energy(model, o, energy_options);
    exo::Fig4EnergyOptions loop_options = energy_options;
    loop_options.loop = true;
    const exo::Fig4Energy loop = exo::runFig4Energy(model, o, loop_options);
    const exo::Fig4Result& r = study.protocol;
    const exo::Fig4Result& rc = study.contact;
    tools::ensureDirectory(out);

    {  // scope: the CSV must be complete (flushed, closed) before the plot script reads it
    std::vector<std::string> columns = {"t_s", "l_x_m", "q_B_rad", "mcp_rad", "pip_rad"};
    for (int m = 0; m < exo::kMethodCount; ++m)
      for (const char* what : {"force_N", "theory_N_per_m", "fd_N_per_m"})
        columns.push_back(std::string(exo::methodKey(m)) + "_" + what);
    columns.push_back("nonlinear_iterations");
    columns.push_back("nonlinear_residual_rad");
    tools::CsvWriter frames(out + "/exo_fig4.csv", columns);
    for (const auto& f : r.frames) {
      std::vector<double> row = {f.t, f.q(0), f.q(1), f.x(0), f.x(1)};
      for (int m = 0; m < exo::kMethodCount; ++m) {
        row.push_back(f.force[m]);
        row.push_back(f.theory[m]);
        row.push_back(f.fd[m]);
      }
      row.push_back(f.nonlinear_iterations);
      row.push_back(f.nonlinear_residual);
      frames.row(row);
    }
    }

    tools::CsvWriter summary(out + "/exo_fig4_summary.csv",
                             {"method", "frames", "theory_passive_pct", "fd_frames", "fd_passive_pct",
                              "max_abs_force_N", "theory_min", "theory_max", "fd_max", "faults"});
    std::printf("Fig. 4 protocol: %zu frames at %.0f Hz, proxy at x = 0, Z_q = %g, Z_x = %.4g I "
                "(avg |J_a| = %.2f rad/m)\n",
                r.frames.size(), o.update_rate_hz, o.zq, r.zx, r.avg_abs_Ja);
    std::printf("%-24s %18s %22s %14s\n", "method", "passive in theory", "passive in practice (FD)", "max |tau_a|");
    for (int m = 0; m < exo::kMethodCount; ++m) {
      const auto& s = r.summary[m];
      summary.row(exo::methodName(m), {double(s.frames), 100.0 * s.theoryShare(), double(s.fd_frames),
                                       100.0 * s.fdShare(), s.max_abs_force, s.theory_min, s.theory_max, s.fd_max,
                                       double(s.faults)});
      std::printf("%-24s %17.1f%% %21.1f%% %12.4g N\n", exo::methodName(m), 100.0 * s.theoryShare(),
                  100.0 * s.fdShare(), s.max_abs_force);
    }
    std::printf("contact variant (proxy at MCP 45, PIP 50 deg, finger within +-%g deg), passive by finite "
                "differences:\n", contact_deg);
    for (int m = 0; m < exo::kMethodCount; ++m) {
      const auto& s = rc.summary[m];
      summary.row(std::string("contact: ") + exo::methodName(m),
                  {double(s.frames), 100.0 * s.theoryShare(), double(s.fd_frames), 100.0 * s.fdShare(),
                   s.max_abs_force, s.theory_min, s.theory_max, s.fd_max, double(s.faults)});
      std::printf("  %-24s %6.1f%% (largest %+.3g N/m)\n", exo::methodName(m), 100.0 * s.fdShare(), s.fd_max);
    }
    std::printf("nonlinear solve: mean %.3f iterations per tick, max %d, max residual %.3g rad\n",
                r.mean_nonlinear_iterations, r.max_nonlinear_iterations, r.max_nonlinear_residual);

    {
      tools::CsvWriter csv(out + "/exo_fig4_energy.csv",
                           {"motion: method", "generated_forward_mJ", "generated_backward_mJ", "field_work_mJ",
                            "hold_share_mJ", "hold_closed_form_mJ", "fine_forward_mJ", "fine_backward_mJ",
                            "stiffening_W", "max_abs_force_N", "faults"});
      std::printf("energy given to the finger (referee, actuator port), policy through the hardware path: %.0f Hz, "
                  "%d period(s) late, force loop %s; Z_x = %.4g N m/rad, Z_q = %.4g N/m; delta = %.3f ms\n",
                  1.0 / energy.options.servo_period_s, energy.options.command_delay,
                  energy.options.force_loop_lag ? "on" : "off", energy.zx, energy.zq, 1e3 * energy.delay_s);
      for (const exo::Fig4Energy* run : {&energy, &loop}) {
        const char* motion = run == &energy ? "fig4" : "loop";
        std::printf("%s motion%s\n%-24s %12s %12s %12s %12s %14s\n", motion,
                    run == &energy ? " (the path back retraces the path out)" : " (MCP and PIP at one period, the PIP a quarter cycle ahead)",
                    "method", "forward", "backward", "field W", "hold share", "hold, delta S");
        for (int m : exo::kPolicyMethods) {
          const exo::Fig4MethodEnergy& e = run->methods[static_cast<std::size_t>(m)];
          const double closed = e.holdClosedForm_mJ(run->delay_s);
          csv.row(std::string(motion) + ": " + exo::methodName(m),
                  {e.forward.generated_mJ, e.backward.generated_mJ, e.fieldWork_mJ(), e.holdShare_mJ(), closed,
                   e.fine_forward.generated_mJ, e.fine_backward.generated_mJ, e.fine_forward.stiffening_W,
                   e.forward.max_abs_force_N, double(e.forward.faults + e.backward.faults)});
          std::printf("%-24s %9.4g mJ %9.4g mJ %9.4g mJ %9.4g mJ %11.4g mJ\n", exo::methodName(m),
                      e.forward.generated_mJ, e.backward.generated_mJ, e.fieldWork_mJ(), e.holdShare_mJ(), closed);
        }
      }
    }

    const experiments::ReproductionTable table = exo::reproductionTable(study, &energy, &loop);
    table.writeCsv(out + "/reproduction.csv");
    std::cout << table.format();
    // The linearized form (eq. 8) is only reported for the Fig. 4 protocol (exo::reproductionTable).
    const auto& lin = r.summary[exo::kSubspaceLinearized];
    if (!lin.fd_frames || lin.fdShare() < 1.0)
      std::cout << "note: with the proxy at x = 0 (up to 95 deg from the finger) the linearized subspace proxy\n"
                   "      (eq. 8) is passive in " << 100.0 * lin.fdShare() << " % of frames on this linkage: the deviation is\n"
                   "      far outside the linearization's validity; the nonlinear form (eq. 6) is passive in all.\n";

    const std::string png = out + "/exo_fig4.png";
    if (tools::runPlotScript("exo_fig4.py", {out + "/exo_fig4.csv", png})) std::cout << "figure: " << png << "\n";
    std::cout << "results in " << out << "\n";
    return table.allPass() ? tools::CommandLine::kAllPass : tools::CommandLine::kRowsFail;
  } catch (const std::exception& e) {
    std::cerr << "uhaptics-exo-fig4: " << e.what() << "\n";
    return tools::CommandLine::kRunError;
  }
}
