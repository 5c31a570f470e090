// uhaptics-tau-study: paper 001's Monte-Carlo wall study on the simulated TAU.
//   uhaptics-tau-study [--full] [--grid N] [--runs M] [--threads T] [--seed S] [--out DIR]
// Default: 3 x 3 query points x 4 runs (seconds); --full: 11 x 11 x 20 as in the paper.
#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include "uhaptics/experiments/parallel.hpp"
#include "uhaptics/experiments/reproduction.hpp"
#include "uhaptics/experiments/tau_study.hpp"
#include "uhaptics/tools/csv.hpp"
#include "uhaptics/tools/plot.hpp"
#include "uhaptics/tools/progress.hpp"

using namespace uhaptics;
using namespace uhaptics::study;

namespace {

// The variants simulated at every (query point, run): same seed, so the comparison is paired.
struct Variant {
  Controller controller;
  Scenario scenario;
  int delay;
  const char* label;
};
const Variant kVariants[] = {
    {Controller::kLqr, Scenario::kStepForce, 0, "lqr_s1"},     {Controller::kSpring, Scenario::kStepForce, 0, "spring_s1"},
    {Controller::kLqr, Scenario::kHand, 0, "lqr_s2"},          {Controller::kSpring, Scenario::kHand, 0, "spring_s2"},
    {Controller::kLqr, Scenario::kStepForce, 3, "lqr_s1_delay"}, {Controller::kLqr, Scenario::kHand, 3, "lqr_s2_delay"},
};
constexpr std::size_t kNumVariants = sizeof(kVariants) / sizeof(kVariants[0]);

std::uint64_t mix(std::uint64_t a, std::uint64_t b) {
  std::uint64_t z = a * 0x9e3779b97f4a7c15ULL + b + 0x632be59bd9b4e019ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

struct Stats {
  double mean = 0.0, stddev = 0.0, min = std::numeric_limits<double>::infinity(), max = -std::numeric_limits<double>::infinity();
};
Stats stats(const std::vector<double>& v) {
  Stats s;
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

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Paper 001 Monte-Carlo study: LQR position-control wall vs spring wall on the simulated TAU"};
  bool full = false;
  int grid = 3, runs = 4;
  unsigned threads = 0;
  std::uint64_t seed = 2021;
  std::string out = "out/tau-study";
  std::string params = std::string(UHAPTICS_PARAMS_DIR) + "/tau.json";
  app.add_flag("--full", full, "the paper's grid: 11 x 11 query points, 20 runs each");
  app.add_option("--grid", grid, "query points per side (x, y in [-25, 25] mm)")->check(CLI::Range(2, 51));
  app.add_option("--runs", runs, "Monte-Carlo runs per query point")->check(CLI::Range(1, 1000));
  app.add_option("--threads", threads, "worker threads (0 = all cores)");
  app.add_option("--seed", seed, "base seed (results are identical for any thread count)");
  app.add_option("--out", out, "output folder");
  app.add_option("--params", params, "device parameter file");
  std::vector<double> weight_list;
  app.add_option("--weights", weight_list, "LQR weights: velocity position integral torque (default: tuned for tau.json)")
      ->expected(4);
  bool paper_weights = false;
  app.add_flag("--paper-weights", paper_weights, "paper 001's weights Q = diag(I, 1e3 I, 1e7 I), R = I");
  // The delay variants' LQR is designed for the delay the plant has, d ~ U{0..3} i.i.d. each period
  // (generalized Riccati equation), with an input-rate weight that keeps the command from
  // chattering between the commands in flight. W = 200: on the full grid's 4840 delay runs 50 and
  // 100 lose the tool or sink 2.3-4.5 mm in 1-2 runs, 200-300 in none, 500-1000 soften the hold
  // (README, TAU section).
  int delay_design = 3;
  app.add_option("--delay-design", delay_design,
                 "largest command delay D (samples) the LQR of the delay variants is designed for (0: the undelayed "
                 "design)")
      ->check(CLI::Range(0, kMaxCommandDelay));
  std::vector<double> delay_weight_list;
  app.add_option("--delay-weights", delay_weight_list, "LQR weights of the delay variants (default: as --weights)")
      ->expected(4);
  bool delay_fixed = false;
  app.add_flag("--delay-fixed", delay_fixed,
               "design the delay variants for a fixed delay of D = --delay-design samples instead of the random "
               "d ~ U{0..D}");
  double delay_rate_weight = 200.0;
  CLI::Option* rate_weight_option = app.add_option("--delay-rate-weight", delay_rate_weight,
                 "random-delay design only: weight on (u_k - u_{k-1})^2 per joint, (N m)^-2")
      ->check(CLI::NonNegativeNumber);
  bool applied_unknown = false;
  app.add_flag("--applied-unknown", applied_unknown,
               "the observer infers the torque the device applied from the delay model instead of the device's "
               "report (the protocol's STATE frame echoes the sequence of the command applied)");
  std::vector<double> delay_observer;
  app.add_option("--delay-observer", delay_observer,
                 "observer noise of the delay variants: velocity, disturbance, position process noise, encoder std "
                 "(0: resolution / sqrt(12))")
      ->expected(4);
  double delay_release = -1.0;
  app.add_option("--delay-release-distance", delay_release,
                 "LQR release height above the wall (m) in the delay variants (default: hold while the environment reports the contact)");
  bool ideal_encoders = false;
  app.add_flag("--ideal-encoders", ideal_encoders, "ideal joint sensors instead of 4096-count encoders (all variants)");
  CLI11_PARSE(app, argc, argv);
  if (rate_weight_option->count() > 0 && (delay_fixed || delay_design == 0)) {
    std::fprintf(stderr, "uhaptics-tau-study: --delay-rate-weight is for the random-delay design (not with "
                         "--delay-fixed or --delay-design 0)\n");
    return 2;
  }
  if (full) {
    grid = 11;
    runs = 20;
  }
  try {
    tools::ensureDirectory(out);
    const TauModel model = TauModel::load(params);
    const auto t_design = std::chrono::steady_clock::now();
    LqrWallWeights weights;  // tuned for our plant (README); --paper-weights for paper 001's own
    if (paper_weights) weights = LqrWallWeights::paper();
    if (!weight_list.empty()) weights = {weight_list[0], weight_list[1], weight_list[2], weight_list[3]};
    const LqrWallGains gains = designLqrWall(model, model.homePose(), weights);
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
    const LqrWallGains delay_gains = designLqrWall(model, model.homePose(), delay_weights, delay_noise, delay_model);
    if (delay_model.random)
      std::printf("random-delay design (d ~ U{0..%d}, rate weight %g): generalized Riccati %d steps, residual %.1e, "
                  "mean-square radius %.4f (state feedback)\n",
                  delay_design, delay_model.rate_weight, delay_gains.dare_iterations, delay_gains.dare_residual,
                  delay_gains.ms_spectral_radius);
    const double design_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t_design).count();
    std::printf("LQR design at the workspace centre, Q = diag(%g I, %g I, %g I), R = %g I: fastest pole %.0f rad/s, "
                "DARE residual %.1e (%d doublings), %.2f ms\n",
                weights.velocity, weights.position, weights.integral, weights.torque, gains.fastest_pole_rad_s,
                gains.dare_residual, gains.dare_iterations, design_ms);

    // Requirement checks of paper 001 section III at the workspace centre: on the design (state
    // feedback, ideal sensor) as the paper checks them, plus the force step as the device runs it,
    // through the renderer's Kalman observer on the 4096-count encoders.
    const StepResponse step = stepReferenceResponse(model, gains, model.homePose(), 1e-3);
    const double deviation = forceStepDeviation(model, gains, model.homePose(), 15.0);
    const double deviation_encoders =
        forceStepDeviation(model, gains, model.homePose(), 15.0, Feedback::kObserverOnEncoders);

    const double half = model.workspaceHalfSide();
    const std::size_t points = static_cast<std::size_t>(grid * grid);
    const std::size_t jobs = points * static_cast<std::size_t>(runs);
    std::vector<RunMetrics> results(jobs * kNumVariants);
    tools::Progress progress("tau-study", jobs);
    const auto t0 = std::chrono::steady_clock::now();
    experiments::parallelFor(jobs, threads, [&](std::size_t job) {
      const std::size_t point = job / static_cast<std::size_t>(runs);
      RunSpec spec;
      spec.x = -half + 2.0 * half * static_cast<double>(point % grid) / (grid - 1);
      spec.y = -half + 2.0 * half * static_cast<double>(point / grid) / (grid - 1);
      spec.seed = mix(seed, job);
      for (std::size_t v = 0; v < kNumVariants; ++v) {
        spec.controller = kVariants[v].controller;
        spec.scenario = kVariants[v].scenario;
        spec.max_delay_samples = kVariants[v].delay;
        spec.quantize = !ideal_encoders;
        spec.lqr_release_distance = kVariants[v].delay > 0 ? delay_release : -1.0;
        spec.applied_torque_known = !applied_unknown;
        results[job * kNumVariants + v] = simulateRun(model, kVariants[v].delay > 0 ? delay_gains : gains, spec);
      }
      progress.advance();
    });
    progress.finish();
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const double simulated = static_cast<double>(results.size()) * 3.0;

    // Per query point statistics, CSV for the heat maps.
    std::vector<std::string> columns = {"x_mm", "y_mm"};
    for (const auto& v : kVariants)
      for (const char* m : {"d_z1_mm", "k_z1", "d_zs_mm", "k_zs", "max_pen_mm", "k_zs_std"})
        columns.push_back(std::string(v.label) + "_" + m);
    int faults = 0;
    std::vector<int> variant_faults(kNumVariants, 0);
    std::vector<double> extreme_min(kNumVariants * 2, std::numeric_limits<double>::infinity());
    std::vector<double> extreme_max(kNumVariants * 2, 0.0);
    std::vector<double> max_pen(kNumVariants, 0.0);
    int delay_runs = 0, delay_runs_over_1mm = 0;  // delay variants; over 1 mm or faulted (the tool was lost)
    {
    tools::CsvWriter csv(out + "/points.csv", columns);  // closed (flushed) before plotting
    for (std::size_t p = 0; p < points; ++p) {
      std::vector<double> row = {1e3 * (-half + 2.0 * half * static_cast<double>(p % grid) / (grid - 1)),
                                 1e3 * (-half + 2.0 * half * static_cast<double>(p / grid) / (grid - 1))};
      for (std::size_t v = 0; v < kNumVariants; ++v) {
        std::vector<double> dz1, kz1, dzs, kzs, pen;
        for (int r = 0; r < runs; ++r) {
          const RunMetrics& m = results[(p * runs + r) * kNumVariants + v];
          faults += m.fault != Fault::kNone;
          variant_faults[v] += m.fault != Fault::kNone;
          if (kVariants[v].delay > 0) {
            ++delay_runs;
            delay_runs_over_1mm += m.max_penetration > 1e-3 || m.fault != Fault::kNone;
          }
          dz1.push_back(m.d_z1);
          kz1.push_back(m.k_z1);
          dzs.push_back(m.d_zs);
          kzs.push_back(m.k_zs);
          pen.push_back(m.max_penetration);
        }
        const Stats sk1 = stats(kz1), sks = stats(kzs), sp = stats(pen);
        row.insert(row.end(), {1e3 * stats(dz1).mean, sk1.mean, 1e3 * stats(dzs).mean, sks.mean, 1e3 * sp.max, sks.stddev});
        // Table IV compares the per-point means: lowest over the wall for p.c., highest for b.c.
        extreme_min[2 * v] = std::min(extreme_min[2 * v], sk1.mean);
        extreme_min[2 * v + 1] = std::min(extreme_min[2 * v + 1], sks.mean);
        extreme_max[2 * v] = std::max(extreme_max[2 * v], sk1.mean);
        extreme_max[2 * v + 1] = std::max(extreme_max[2 * v + 1], sks.mean);
        max_pen[v] = std::max(max_pen[v], sp.max);
      }
      csv.row(row);
    }
    }

    // Table IV style summary. Our geometry and masses differ from the real TAU (unpublished), so
    // the absolute numbers are not expected to match; what must carry over is judged instead.
    experiments::ReproductionTable table;
    const double lqr_kz1_low = extreme_min[0], spring_kz1_high = extreme_max[2];
    const double lqr_kzs1_low = extreme_min[1], spring_kzs1_high = extreme_max[3];
    const double lqr_kzs2_low = extreme_min[5], spring_kzs2_high = extreme_max[7];
    table.add({"001", "fastest closed-loop pole", 2480.0, gains.fastest_pole_rad_s, "within 10 %",
               std::abs(gains.fastest_pole_rad_s - 2480.0) <= 248.0, "rad/s"});
    table.add({"001", "sc.1 lowest K_z1, LQR", 17174.0, lqr_kz1_low, ">= 3x highest spring K_z1 (paper 5.5x)",
               lqr_kz1_low >= 3.0 * spring_kz1_high, "N/m"});
    table.add({"001", "sc.1 highest K_z1, spring", 3112.6, spring_kz1_high, "within 30 % (device mass differs)",
               std::abs(spring_kz1_high - 3112.6) <= 0.3 * 3112.6, "N/m"});
    table.add({"001", "sc.1 lowest K_zs, LQR", 92387.0, lqr_kzs1_low, ">= 10x highest spring K_zs (paper 15x)",
               lqr_kzs1_low >= 10.0 * spring_kzs1_high, "N/m"});
    table.add({"001", "sc.1 highest K_zs, spring", 6180.5, spring_kzs1_high, "within 15 % of 6000 N/m design",
               std::abs(spring_kzs1_high - 6180.5) <= 0.15 * 6180.5, "N/m"});
    table.add({"001", "sc.2 lowest K_zs, LQR", 65002.0, lqr_kzs2_low, ">= 10x highest spring K_zs (paper 10x)",
               lqr_kzs2_low >= 10.0 * spring_kzs2_high, "N/m"});
    table.add({"001", "sc.2 highest K_zs, spring", 6202.1, spring_kzs2_high, "within 15 %",
               std::abs(spring_kzs2_high - 6202.1) <= 0.15 * 6202.1, "N/m"});
    const double lqr_pen = std::max(max_pen[0], max_pen[2]);
    table.addBound("001", "max penetration, LQR", 1e3 * lqr_pen, "< 1 mm", lqr_pen < 1e-3, "mm");
    const double delay_pen = std::max(max_pen[4], max_pen[5]);
    table.addBound("001", "max penetration, LQR, delay 0-3", 1e3 * delay_pen, "< 1.1 mm (paper CoS-D)", delay_pen < 1.1e-3, "mm");
    // Paper 001's CoS-D: 3 of its 90 runs (scenario 1) above 1 mm.
    const double delay_over_share = 100.0 * static_cast<double>(delay_runs_over_1mm) / static_cast<double>(delay_runs);
    table.addBound("001", "runs above 1 mm, LQR, delay 0-3", delay_over_share, "<= 3.3 % (paper CoS-D: 3 of 90)",
                   delay_over_share <= 100.0 * 3.0 / 90.0, "%");
    table.addBound("001", "step reference overshoot", step.overshoot_percent, "< 2 %", step.overshoot_percent < 2.0, "%");
    table.addBound("001", "step reference rise time", step.rise_time, "< 0.05 s", step.rise_time < 0.05, "s");
    table.addBound("001", "step reference settling time", step.settling_time, "< 0.1 s", step.settling_time < 0.1, "s");
    table.addBound("001", "15 N force step, max joint deviation", deviation, "< 0.001 rad", deviation < 1e-3, "rad");
    // The device senses the joints to one encoder count (0.0015 rad), coarser than the paper's
    // 0.001 rad bound, so the loop it runs is held to the bound plus one count of sensing error.
    const double encoder_bound = 1e-3 + model.encoderResolution();
    char criterion[64];
    std::snprintf(criterion, sizeof criterion, "< 0.001 rad + 1 count (%.4f rad)", encoder_bound);
    table.addBound("001", "15 N force step, observer on the encoders", deviation_encoders, criterion,
                   deviation_encoders < encoder_bound, "rad");
    table.writeCsv(out + "/reproduction.csv");
    std::printf("\n%s\n", table.format().c_str());
    std::printf("%zu query points x %d runs x %zu variants = %zu runs of 3 s; faults: %d\n", points, runs, kNumVariants,
                results.size(), faults);
    for (std::size_t v = 0; v < kNumVariants; ++v)
      std::printf("  %-13s faults %3d / %zu, max penetration %.3f mm\n", kVariants[v].label, variant_faults[v], jobs,
                  1e3 * max_pen[v]);
    std::printf("wall time %.2f s on %u threads: %.0f simulated seconds per second\n", wall,
                threads ? threads : experiments::hardwareThreads(), simulated / wall);

    // One trace per controller at the centre (Fig. 8/9 style) and the heat maps (Fig. 10, 12, 13).
    for (const Scenario sc : {Scenario::kStepForce, Scenario::kHand}) {
      tools::CsvWriter trace_csv(out + "/trace_s" + std::to_string(static_cast<int>(sc)) + ".csv",
                                 {"t", "lqr_z_mm", "spring_z_mm", "force_n"});
      std::vector<TraceSample> a, b;
      RunSpec spec;
      spec.scenario = sc;
      spec.seed = mix(seed, 0);
      spec.controller = Controller::kLqr;
      simulateRun(model, gains, spec, {}, &a);
      spec.controller = Controller::kSpring;
      simulateRun(model, gains, spec, {}, &b);
      for (std::size_t i = 0; i < std::min(a.size(), b.size()); ++i)
        trace_csv.row({a[i].t, 1e3 * a[i].z, 1e3 * b[i].z, a[i].force});
    }  // trace files closed here
    tools::runPlotScript("tau_study.py", {out});
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "uhaptics-tau-study: %s\n", e.what());
    return 1;
  }
}
