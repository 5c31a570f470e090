// uhaptics-tau-study: paper 001's Monte-Carlo wall study on the simulated TAU.
//   uhaptics-tau-study [--full] [--grid N] [--runs M] [--threads T] [--seed S] [--out DIR]
// Default: 3 x 3 query points x 4 runs (seconds); --full: 11 x 11 x 20 as in the paper.
#include <CLI/CLI.hpp>
#include <chrono>
#include <ctime>
#include <algorithm>
#include <cstdio>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "device_servo_renderers.hpp"  // the devices' policy factory (tools/servo)
#include "uhaptics/backends/board_catalog.hpp"
#include "uhaptics/backends/params_location.hpp"
#include "uhaptics/experiments/parallel.hpp"
#include "uhaptics/experiments/reproduction.hpp"
#include "uhaptics/experiments/tau_study.hpp"
#include "uhaptics/tools/cli.hpp"
#include "uhaptics/tools/csv.hpp"
#include "uhaptics/tools/plot.hpp"
#include "uhaptics/tools/progress.hpp"

using namespace uhaptics;
using namespace uhaptics::study;

namespace {
// LQR weights: positive (a zero weight leaves the Riccati equation without a unique solution) and
// within the range the DARE solver is tested over (paper 001's integral weight is 1e7).
constexpr double kMinWeight = 1e-9, kMaxWeight = 1e12;
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Paper 001 Monte-Carlo study: LQR position-control wall vs spring wall on the simulated TAU"};
  bool full = false;
  int grid = 3, runs = 4;
  unsigned threads = 0;
  std::uint64_t seed = 2021;
  std::string out = "out/tau-study";
  std::string params = defaultParamsDirectory() + "/tau.json";
  app.footer(tools::CommandLine::kExitCodesHelp);
  tools::CommandLine cli(app, "uhaptics-tau-study");
  app.add_flag("--full", full, "the paper's grid: 11 x 11 query points, 20 runs each");
  cli.integer("--grid", grid, "query points per side (x, y in [-25, 25] mm)", 2, 51);
  cli.integer("--runs", runs, "Monte-Carlo runs per query point", 1, 1000);
  cli.integer("--threads", threads, "worker threads (0 = all cores)", 0, experiments::kMaxThreads);
  cli.integer("--seed", seed, "base seed (results are identical for any thread count)", 0,
              std::numeric_limits<long long>::max());
  cli.outputFolder("--out", out, "output folder");
  cli.inputFile("--params", params, "device parameter file");
  std::vector<double> weight_list;
  cli.numbers("--weights", weight_list, 4, "LQR weights: velocity position integral torque (default: tuned for tau.json)",
              kMinWeight, kMaxWeight);
  bool paper_weights = false;
  app.add_flag("--paper-weights", paper_weights, "paper 001's weights Q = diag(I, 1e3 I, 1e7 I), R = I");
  // The delay variants' LQR is designed for the delay the plant has, d ~ U{0..3} i.i.d. each period
  // (generalized Riccati equation), with an input-rate weight that keeps the command from
  // chattering between the commands in flight. W = 200: on the full grid's 4840 delay runs 50 and
  // 100 lose the tool or sink 2.3-4.5 mm in 1-2 runs, 200-300 in none, 500-1000 soften the hold
  // (README, TAU section).
  int delay_design = 3;
  cli.integer("--delay-design", delay_design,
              "largest command delay D (samples) the LQR of the delay variants is designed for (0: the undelayed "
              "design)", 0, kMaxCommandDelay);
  std::vector<double> delay_weight_list;
  cli.numbers("--delay-weights", delay_weight_list, 4, "LQR weights of the delay variants (default: as --weights)",
              kMinWeight, kMaxWeight);
  bool delay_fixed = false;
  app.add_flag("--delay-fixed", delay_fixed,
               "design the delay variants for a fixed delay of D = --delay-design samples instead of the random "
               "d ~ U{0..D}");
  double delay_rate_weight = 200.0;
  CLI::Option* rate_weight_option = cli.number("--delay-rate-weight", delay_rate_weight,
                 "random-delay design only: weight on (u_k - u_{k-1})^2 per joint, (N m)^-2", 0.0, kMaxWeight);
  bool applied_unknown = false;
  app.add_flag("--applied-unknown", applied_unknown,
               "the wall's observer takes the delay model's expected torque instead of the command the board names "
               "as applied (the protocol's STATE frame: last_command_sequence)");
  std::vector<double> delay_observer;
  cli.numbers("--delay-observer", delay_observer, 4,
              "observer noise of the delay variants: velocity, disturbance, position process noise, encoder std "
              "(0: resolution / sqrt(12))", 0.0, 1e6);
  double delay_release = -1.0;
  // Within the 50 mm workspace cube (tau.json): a release higher than the workspace never happens.
  cli.number("--delay-release-distance", delay_release,
             "LQR release height above the wall (m) in the delay variants (default: hold while the environment "
             "reports the contact)", 0.0, 0.05);
  int substeps = 0;
  cli.integer("--substeps", substeps,
              "plant integration substeps per servo period in the grid runs (default: the parameter file's)", 1, 1000);
  double relinearize = GridOptions{}.relinearize_tolerance;
  std::ostringstream relinearize_default;
  relinearize_default << relinearize;
  cli.number("--relinearize", relinearize,
             "joint travel (rad) after which the grid runs' plant solves its dynamics and pose again (0: every "
             "period; default " + relinearize_default.str() + ")", 0.0, 0.01);
  bool ideal_encoders = false;
  app.add_flag("--ideal-encoders", ideal_encoders, "ideal joint sensors instead of 4096-count encoders (all variants)");
  if (const int status = cli.parse(argc, argv); status >= 0) return status;
  if (rate_weight_option->count() > 0 && (delay_fixed || delay_design == 0)) {
    std::fprintf(stderr, "uhaptics-tau-study: --delay-rate-weight is for the random-delay design (not with "
                         "--delay-fixed or --delay-design 0)\n");
    return tools::CommandLine::kRunError;
  }
  if (full) {
    grid = 11;
    runs = 20;
  }
  try {
    const TauModel model = TauModel::load(params);
    tools::ensureDirectory(out);  // after the parameter file is read: a refused file leaves no folder
    const auto t_design = std::chrono::steady_clock::now();
    LqrWallWeights weights;  // tuned for our plant (README); --paper-weights for paper 001's own
    if (paper_weights) weights = LqrWallWeights::paper();
    if (!weight_list.empty()) weights = {weight_list[0], weight_list[1], weight_list[2], weight_list[3]};
    const LqrWallDesign design = designLqrWall(model, model.homePose(), weights);
    const LqrWallGains& gains = design.gains;
    LqrWallWeights delay_weights = weights;
    if (!delay_weight_list.empty())
      delay_weights = {delay_weight_list[0], delay_weight_list[1], delay_weight_list[2], delay_weight_list[3]};
    // The delay variants run the design on the plant augmented with the commands in flight.
    CommandDelayDesign delay_model;
    delay_model.samples = delay_design;
    delay_model.random = !delay_fixed && delay_design > 0;
    delay_model.rate_weight = delay_model.random ? delay_rate_weight : 0.0;
    ObserverNoise delay_noise;
    if (!delay_observer.empty())
      delay_noise = {delay_observer[0], delay_observer[1], delay_observer[2], delay_observer[3]};
    const LqrWallDesign delay_wall = designLqrWall(model, model.homePose(), delay_weights, delay_noise, delay_model);
    if (delay_model.random)
      std::printf("random-delay design (d ~ U{0..%d}, rate weight %g): generalized Riccati %d steps, residual %.1e, "
                  "mean-square radius %.4f (state feedback)\n",
                  delay_design, delay_model.rate_weight, delay_wall.report.dare_iterations, delay_wall.report.dare_residual,
                  delay_wall.report.ms_spectral_radius);
    const double design_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t_design).count();
    std::printf("LQR design at the workspace centre, Q = diag(%g I, %g I, %g I), R = %g I: fastest pole %.0f rad/s, "
                "DARE residual %.1e (%d doublings), %.2f ms\n",
                weights.velocity, weights.position, weights.integral, weights.torque, design.report.fastest_pole_rad_s,
                design.report.dare_residual, design.report.dare_iterations, design_ms);

    const Requirements requirements = checkRequirements(model, gains);

    // The study runs the product: the TAU's policy from the devices' factory, on its board's spec.
    std::string params_dir = ".", params_file = params;
    if (const auto slash = params.find_last_of('/'); slash != std::string::npos) {
      params_dir = params.substr(0, slash);
      params_file = params.substr(slash + 1);
    }
    const DeviceDefinition* registered = findDeviceByPaper("001");
    if (registered == nullptr) throw Error("no registered device reproduces paper 001");
    DeviceDefinition tau = *registered;
    tau.params_file = params_file;
    const TauProduct product{[&tau, &params_dir] { return makeDevicePolicy(tau, params_dir); }, boardSpec(tau, params_dir)};
    StudyDesigns designs;
    const double contact_band = StudyParameters{}.contact_band;
    designs.undelayed = studyWallDesign(weights, contact_band);
    designs.delayed = studyWallDesign(delay_weights, contact_band);
    designs.delayed.custom_observer_noise = true;
    designs.delayed.observer_noise = delay_noise;
    designs.delayed.random_delay = delay_model.random;
    designs.delayed.delay_rate_weight = delay_model.rate_weight;
    if (delay_release >= 0.0) designs.delayed.renderer.release_distance = delay_release;
    designs.delay_samples = delay_design;

    GridOptions grid_options;
    grid_options.grid = grid;
    grid_options.runs = runs;
    grid_options.threads = threads;
    grid_options.seed = seed;
    grid_options.quantize = !ideal_encoders;
    grid_options.applied_command_reported = !applied_unknown;
    grid_options.substeps = substeps;
    grid_options.relinearize_tolerance = relinearize;
    const std::size_t jobs = static_cast<std::size_t>(grid * grid) * static_cast<std::size_t>(runs);
    tools::Progress progress("tau-study", jobs);
    const auto t0 = std::chrono::steady_clock::now();
    const std::clock_t cpu0 = std::clock();  // process CPU time, all threads
    const GridStudy study = runGrid(model, product, designs, grid_options, [&] { progress.advance(); });
    progress.finish();
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const double cpu = static_cast<double>(std::clock() - cpu0) / CLOCKS_PER_SEC;
    const double simulated = static_cast<double>(study.simulated_runs) * 3.0;

    // Per query point statistics, CSV for the heat maps.
    const auto& variants = studyVariants();
    std::vector<std::string> columns = {"x_mm", "y_mm"};
    for (const auto& v : variants)
      for (const char* m : {"d_z1_mm", "k_z1", "d_zs_mm", "k_zs", "max_pen_mm", "k_zs_std"})
        columns.push_back(std::string(v.label) + "_" + m);
    {
      tools::CsvWriter csv(out + "/points.csv", columns);  // closed (flushed) before plotting
      for (const GridPoint& p : study.points) {
        std::vector<double> row = {1e3 * p.x, 1e3 * p.y};
        for (const PointStatistics& s : p.variants)
          row.insert(row.end(), {1e3 * s.d_z1.mean, s.k_z1.mean, 1e3 * s.d_zs.mean, s.k_zs.mean, 1e3 * s.penetration.max,
                                 s.k_zs.stddev});
        csv.row(row);
      }
    }

    const experiments::ReproductionTable table = reproductionTable(model, design, requirements, study);
    table.writeCsv(out + "/reproduction.csv");
    std::printf("\n%s\n", table.format().c_str());
    std::printf("%zu query points x %d runs x %zu variants = %zu runs of 3 s; faults: %d\n", study.points.size(), runs,
                kNumVariants, study.simulated_runs, study.faults);
    for (std::size_t v = 0; v < kNumVariants; ++v)
      std::printf("  %-13s faults %3d / %zu, max penetration %.3f mm; referee: max true penetration %.3f mm, most "
                  "energy given to the user in a run %.1f mJ\n",
                  variants[v].label, study.variant_faults[v], jobs, 1e3 * study.max_penetration[v],
                  1e3 * study.referee_max_penetration[v], study.referee_max_energy[v]);
    std::printf("wall time %.2f s on %u threads: %.0f simulated seconds per second; CPU %.1f s (%.1f us per "
                "simulated servo period)\n",
                wall, threads ? threads : experiments::hardwareThreads(), simulated / wall, cpu,
                1e6 * cpu / (simulated / model.servoPeriod()));

    // One trace per controller at the centre (Fig. 8/9 style) and the heat maps (Fig. 10, 12, 13).
    for (const Scenario sc : {Scenario::kStepForce, Scenario::kHand}) {
      tools::CsvWriter trace_csv(out + "/trace_s" + std::to_string(static_cast<int>(sc)) + ".csv",
                                 {"t", "lqr_z_mm", "spring_z_mm", "force_n"});
      const CentreTraces traces = centreTraces(model, product, designs.undelayed, sc, seed);
      const std::vector<TraceSample>& a = traces.lqr;
      const std::vector<TraceSample>& b = traces.spring;
      for (std::size_t i = 0; i < std::min(a.size(), b.size()); ++i)
        trace_csv.row({a[i].t, 1e3 * a[i].z, 1e3 * b[i].z, a[i].force});
    }  // trace files closed here
    tools::runPlotScript("tau_study.py", {out});
    return table.allPass() ? tools::CommandLine::kAllPass : tools::CommandLine::kRowsFail;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "uhaptics-tau-study: %s\n", e.what());
    return tools::CommandLine::kRunError;
  }
}
