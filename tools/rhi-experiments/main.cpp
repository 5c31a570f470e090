// uhaptics-rhi-experiments: paper 003 on the simulated 4-DoF redundant haptic interface and the
// 3-DoF example arm. Writes CSV + PNG per study, summary.txt and reproduction.csv into --out.
// Exit status 0 when every check of reproduction.csv passes, 1 when one fails, 2 on error (as
// tools/run-main reads it: the other experiments still run after a 1).
#include <CLI/CLI.hpp>
#include <cmath>
#include <fstream>
#include <iostream>

#include "device_servo_renderers.hpp"  // the devices' policy factory (tools/servo)
#include "uhaptics/backends/board_catalog.hpp"
#include "uhaptics/backends/params_location.hpp"
#include "uhaptics/experiments/parallel.hpp"
#include "uhaptics/experiments/reproduction.hpp"
#include "uhaptics/experiments/rhi_experiments.hpp"
#include "uhaptics/tools/cli.hpp"
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

void writePalpation(const rhi::PalpationCase& free_case, const rhi::PalpationCase& stiff_case, const std::string& dir) {
  CsvWriter t(dir + "/palpation_table.csv",
              {"ellipsoid", "q1", "q2", "q3", "q4", "capability_N", "peak_force_N", "inertia_model_kg",
               "inertia_identified_kg", "friction_model_Ns_per_m", "friction_reference_Ns_per_m",
               "friction_identified_Ns_per_m", "coulomb_model_N", "coulomb_reference_N", "coulomb_identified_N",
               "fit_rms_N", "limit_distance_rad"});
  for (const auto* c : {&free_case, &stiff_case})
    t.row(c->name, {c->q_settled(0), c->q_settled(1), c->q_settled(2), c->q_settled(3), c->capability, c->peak_force,
                    c->inertia_model, c->inertia_identified, c->friction_model, c->friction_reference,
                    c->friction_identified, c->coulomb_model, c->coulomb_reference, c->coulomb_identified, c->fit_rms,
                    c->limit_distance});
  writeLoop(free_case.push, dir + "/palpation_free.csv", 5);
  writeLoop(stiff_case.push, dir + "/palpation_stiff.csv", 5);
  CsvWriter id(dir + "/identification.csv",
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

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Paper 003: force-manipulability null-space control of a redundant planar haptic interface"};
  std::string out = "out/rhi-experiments";
  std::string params = defaultParamsDirectory();
  bool full = false;
  int trials = 10;
  unsigned threads = 0;
  app.footer(tools::CommandLine::kExitCodesHelp);
  tools::CommandLine cli(app, "uhaptics-rhi-experiments");
  cli.outputFolder("--out", out, "Output folder")->capture_default_str();
  cli.inputFolder("--params", params, "Folder with rhi4.json and planar3.json")->capture_default_str();
  cli.integer("--trials", trials, "Identification pushes per ellipsoid (paper: 10)", 2, 100);
  cli.integer("--threads", threads, "Threads for the workspace map (0 = all cores)", 0, experiments::kMaxThreads);
  app.add_flag("--full", full, "Fine workspace grid (1 cm instead of 2.5 cm)");
  if (const int status = cli.parse(argc, argv); status >= 0) return status;

  try {
    const Rhi4Model model = rhi::loadRhi4(params);
    const Planar3Model arm3 = rhi::loadPlanar3(params);
    tools::ensureDirectory(out);  // after the parameter files are read: a refused file leaves no folder
    // The closed-loop studies run the product: the RHI's policy from the devices' factory.
    const DeviceDefinition& rhi_device = findDevice("rhi");
    const experiments::DeviceProduct product{[&] { return makeDevicePolicy(rhi_device, params); },
                                             boardSpec(rhi_device, params)};
    const rhi::Studies studies = rhi::runStudies(model, product, arm3, {trials, full ? 0.01 : 0.025, threads});

    // 3-DoF example (Fig. 3-4).
    writeExample(studies.example, arm3, out);
    tools::runPlotScript("rhi_example3.py", {out + "/example3_torques.csv", out + "/example3_configurations.csv",
                                            out + "/example3.png"});

    // Palpation (Table I): free vs stiff ellipsoid.
    writePalpation(studies.free_case, studies.stiff_case, out);
    tools::runPlotScript("rhi_palpation.py", {out, out + "/palpation.png"});

    // Workspace map (Fig. 10).
    {
      CsvWriter w(out + "/workspace_ratio.csv",
                  {"kind", "x", "y", "free_force", "stiff_force", "ratio", "global_ratio", "free_cost_excess",
                   "stiff_cost_excess", "free_limit_distance", "stiff_limit_distance", "free_bound", "stiff_bound",
                   "rematched"});
      for (const auto& p : studies.map)
        w.row(rhi::toString(p.kind), {p.x(0), p.x(1), p.free_force, p.stiff_force, p.ratio, p.global_ratio,
                                      p.free_cost_excess, p.stiff_cost_excess, p.free_limit_distance,
                                      p.stiff_limit_distance, static_cast<double>(p.free_bound),
                                      static_cast<double>(p.stiff_bound), p.rematched ? 1.0 : 0.0});
    }
    tools::runPlotScript("rhi_workspace.py", {out + "/workspace_ratio.csv", out + "/workspace_ratio.png"});

    // Transition with and without smoothing (Fig. 11).
    writeLoop(studies.smooth.samples, out + "/transition_smooth.csv", 2);
    writeLoop(studies.abrupt.samples, out + "/transition_abrupt.csv", 2);
    tools::runPlotScript("rhi_transition.py", {out + "/transition_smooth.csv", out + "/transition_abrupt.csv",
                                              out + "/transition.png"});

    const experiments::ReproductionTable table = rhi::reproductionTable(studies);
    const std::string summary = rhi::summary(studies);
    table.writeCsv(out + "/reproduction.csv");
    std::ofstream(out + "/summary.txt") << summary;
    std::cout << summary << "\n" << table.format() << "\n";
    return table.allPass() ? tools::CommandLine::kAllPass : tools::CommandLine::kRowsFail;
  } catch (const std::exception& e) {
    std::cerr << "uhaptics-rhi-experiments: " << e.what() << "\n";
    return tools::CommandLine::kRunError;
  }
}
