// uhaptics-zwidth: the Z-width of every registered device (and of the 1-DoF mass-damper whose
// boundary is known in closed form): the largest passive stiffness of a joint-space wall per servo
// rate, command delay and wall damping, with and without the passivity controller, beside the
// analytic bounds of Colgate and Brown (1994) and Abbott and Okamura (2005).
//   uhaptics-zwidth [--device NAME|all] [--rates HZ...] [--max-delay D] [--passivity both|on|off]
//                   [--damping-fractions F...] [--precision P] [--joint J] [--threads T] [--out DIR]
//                   [--task on|off|only]
// Writes devices.csv, boundaries.csv, runs.csv, zwidth_<device>.png, summary.txt and reproduction.csv
// (the boundary against Colgate and Brown where the bound applies, the passivity controller's gain)
// into --out; with --task (on by default) also the task-space wall at the tool (task_zwidth.hpp):
// task_boundaries.csv, stiffness.csv (the m_maxLinearStiffness it recommends per device and rate),
// zwidth_task_<device>.png and their rows in summary.txt. Exit status as the experiment tools: 0
// every row passes, 1 one fails, 2 an error.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <iomanip>
#include <limits>
#include <string>
#include <vector>

#include "uhaptics/backends/device_definition.hpp"
#include "uhaptics/backends/params_location.hpp"
#include "uhaptics/experiments/parallel.hpp"
#include "uhaptics/experiments/task_zwidth.hpp"
#include "uhaptics/experiments/zwidth.hpp"
#include "uhaptics/tools/cli.hpp"
#include "uhaptics/tools/csv.hpp"
#include "uhaptics/tools/plot.hpp"
#include "uhaptics/tools/progress.hpp"
#include "zwidth_devices.hpp"

using namespace uhaptics;
using namespace uhaptics::experiments;

namespace {

constexpr const char* kMassDamper = "mass-damper";
const Boundary* findCase(const DeviceZWidth& r, double rate, int delay, bool passivity) {
  for (const Boundary& b : r.boundaries)
    if (b.wall.rate_hz == rate && b.wall.delay == delay && b.wall.damping == 0.0 && b.wall.passivity == passivity)
      return &b;
  return nullptr;
}

// printf into a string.
__attribute__((format(printf, 2, 3))) void appendf(std::string& out, const char* format, ...) {
  char buf[512];
  va_list args;
  va_start(args, format);
  std::vsnprintf(buf, sizeof buf, format, args);
  va_end(args);
  out += buf;
}

// The recommended m_maxLinearStiffness is this fraction of the measured task-space K_max: the K_max
// is where the wall stops being passive for the scripted hand's damping (zero margin), bisected to
// 2 %, and a lighter grip than the simulated hand's has less damping, so proportionally less K.
constexpr double kStiffnessMargin = 0.8;

// A renderer's task K_max of a device at (rate, delay); NaN when not swept.
double taskStiffness(const DeviceTaskZWidth& r, double rate, int delay, const std::string& renderer = "spring") {
  for (const TaskBoundary& b : r.boundaries)
    if (b.rate_hz == rate && b.delay == delay && b.renderer == renderer) return b.k_max;
  return std::nan("");
}

void writeTaskCsv(const std::string& out, const std::vector<DeviceTaskZWidth>& results) {
  // renderer: the device's own ("spring": J^T F) or the TAU's LQR wall; bound: 2 b_n / ((1 + 2 d) T);
  // above_range: passive up to the search's ceiling (k_max a lower bound).
  std::ofstream csv(out + "/task_boundaries.csv");
  csv << std::setprecision(std::numeric_limits<double>::max_digits10);
  csv << "device,rate_hz,delay,renderer,k_max,bound,ratio,k_fail,below_range,above_range,b_n,hand_damping,"
         "rendered_stiffness,k_stable,rendered_stable,energy_stable,runs\n";
  for (const DeviceTaskZWidth& r : results)
    for (const TaskBoundary& b : r.boundaries)
      csv << r.name << ',' << b.rate_hz << ',' << b.delay << ',' << b.renderer << ',' << b.k_max << ',' << b.k_colgate
          << ',' << (b.k_colgate > 0.0 ? b.k_max / b.k_colgate : std::nan("")) << ',' << b.k_fail << ','
          << (b.below_range ? 1 : 0) << ',' << (b.above_range ? 1 : 0) << ',' << b.b_n << ',' << r.hand_damping << ','
          << b.rendered_stiffness << ',' << b.k_stable << ',' << b.rendered_stable << ',' << b.energy_stable << ','
          << b.runs.size() << '\n';
  if (!csv) throw Error(out + "/task_boundaries.csv: cannot write");
  // outcome: 0 passive, 1 active, 2 limit cycle, 3 divergent.
  std::ofstream runs(out + "/task_runs.csv");
  runs << std::setprecision(std::numeric_limits<double>::max_digits10);
  runs << "device,rate_hz,delay,renderer,stiffness,outcome,generated_energy,tolerance,press_force,max_penetration,"
          "hold_penetration,hold_amplitude,hold_entries,final_amplitude,final_entries,rendered_stiffness\n";
  for (const DeviceTaskZWidth& r : results)
    for (const TaskBoundary& b : r.boundaries)
      for (const TaskWallRun& run : b.runs)
        runs << r.name << ',' << b.rate_hz << ',' << b.delay << ',' << b.renderer << ',' << run.stiffness << ','
             << static_cast<int>(run.outcome) << ',' << run.generated_energy << ',' << run.tolerance << ','
             << run.press_force << ',' << run.max_penetration << ',' << run.hold_penetration << ','
             << run.hold_amplitude << ',' << run.hold_entries << ',' << run.final_amplitude << ','
             << run.final_entries << ',' << run.rendered_stiffness << '\n';
  if (!runs) throw Error(out + "/task_runs.csv: cannot write");
  // recommended: at delay 0 (the "sim" backend); the _delay1 pair for the board protocol's one period.
  tools::CsvWriter stiffness(out + "/stiffness.csv", {"device", "rate_hz", "k_max_task", "recommended",
                                                      "k_max_task_delay1", "recommended_delay1"});
  for (const DeviceTaskZWidth& r : results)
    for (const TaskBoundary& b : r.boundaries)
      if (b.delay == 0 && b.renderer == "spring") {
        const double late = taskStiffness(r, b.rate_hz, 1);
        stiffness.row(r.name, {b.rate_hz, b.k_max, kStiffnessMargin * b.k_max, late, kStiffnessMargin * late});
      }
}

// The task-space rows of summary.txt.
std::string taskSummaryText(const std::vector<DeviceTaskZWidth>& results) {
  std::string out;
  appendf(out, "\nTask space: a wall at the tool, normal +z (device frame), CHAI3D's spring F = K p n through each "
               "device's policy; the user a force source with the hand's damping b_h on the tool.\n");
  appendf(out, "%-12s %-7s %8s %5s %12s %12s %7s %10s %12s %12s %12s\n", "device", "wall", "rate Hz", "delay",
          "K_max N/m", "2 b_n/T", "ratio", "b_n N s/m", "rendered N/m", "K_stable", "rendered");
  for (const DeviceTaskZWidth& r : results) {
    if (!r.note.empty()) {
      appendf(out, "%-12s  %s\n", r.name.c_str(), r.note.c_str());
      continue;
    }
    for (const TaskBoundary& b : r.boundaries)
      appendf(out, "%-12s %-7s %8.0f %5d %11.4g%s %12.4g %7.3f %10.4g %12.4g %12.4g %12.4g\n", r.name.c_str(),
              b.renderer.c_str(), b.rate_hz, b.delay, b.k_max, b.above_range ? "+" : b.below_range ? "-" : " ",
              b.k_colgate, b.k_colgate > 0.0 ? b.k_max / b.k_colgate : std::nan(""), b.b_n, b.rendered_stiffness,
              b.k_stable, b.rendered_stable);
  }
  // appendf's buffer holds 512 characters: one sentence a call.
  appendf(out, "b_n: damping along n identified with a sinusoidal force on the tool at the rate's contact frequency "
               "(hand b_h included); 2 b_n/T: with a delay of d periods 2 b_n / ((1 + 2 d) T). ");
  appendf(out, "rendered: press force / mean sensed penetration at the end of the hold (the LQR wall's stiffness; "
               "about K for the spring); '+': passive to the search's ceiling; '-': nothing passive down to its "
               "floor. ");
  appendf(out, "K_stable: the largest K tried below every bouncing or diverging run (it may be active: the LQR wall "
               "pushes the tool back up to its plane against the user), bracketed within 2x. The LQR wall is "
               "designed for the TAU's 1 kHz only.\n");
  const std::string passive = std::string("spring") + kPassivitySuffix;
  bool layered = false;
  for (const DeviceTaskZWidth& r : results)
    for (const TaskBoundary& b : r.boundaries) layered = layered || b.renderer == passive;
  if (layered) {
    appendf(out, "\nThe passivity layer at the tool (%s: PassivePolicy set up as the CHAI3D adapter sets it up, from "
                 "the board's effort limits and sensor resolution and the parameter file's damping), K_max with it "
                 "over K_max without it:\n", passive.c_str());
    appendf(out, "%-12s %8s %12s %12s\n", "device", "rate Hz", "delay 0", "delay 1");
    for (const DeviceTaskZWidth& r : results)
      for (const TaskBoundary& b : r.boundaries)
        if (b.renderer == passive && b.delay == 0) {
          const double now = b.k_max / taskStiffness(r, b.rate_hz, 0);
          const double late = taskStiffness(r, b.rate_hz, 1, passive) / taskStiffness(r, b.rate_hz, 1);
          appendf(out, "%-12s %8.0f %12.3g %12.3g\n", r.name.c_str(), b.rate_hz, now, late);
        }
    appendf(out, "nan: nothing passive with the layer down to the search's floor. The layer observes the scene's "
                 "share of the command against the scene's own continuous-time work, so what the press stores does "
                 "not hide a ring and the devices' own fields stay off its balance (docs/passivity.md).\n");
  }
  std::vector<double> rates;
  for (const DeviceTaskZWidth& r : results)
    for (const TaskBoundary& b : r.boundaries)
      if (std::find(rates.begin(), rates.end(), b.rate_hz) == rates.end()) rates.push_back(b.rate_hz);
  std::sort(rates.begin(), rates.end());
  for (const int delay : {0, 1}) {
    appendf(out, "\nRecommended m_maxLinearStiffness [N/m] = %.2g x the spring's task K_max at delay %d (%s):\n",
            kStiffnessMargin, delay, delay == 0 ? "the sim backend" : "the board protocol's one period");
    appendf(out, "%-12s", "device");
    for (const double rate : rates) appendf(out, " %9.0f Hz", rate);
    appendf(out, "\n");
    for (const DeviceTaskZWidth& r : results) {
      if (!r.note.empty()) continue;
      appendf(out, "%-12s", r.name.c_str());
      for (const double rate : rates) appendf(out, " %12.4g", kStiffnessMargin * taskStiffness(r, rate, delay));
      appendf(out, "\n");
    }
  }
  return out;
}

/// The passivity layer's check (checkPassivityLayer) as a table.
std::string layerCheckText(const std::vector<TaskLayerCheck>& checks) {
  std::string out;
  if (checks.empty()) return out;
  appendf(out, "\nThe spring wall at twice its K_max without the layer (passive: generated energy within the "
               "tolerance, no bounce, the kick's ring decays):\n");
  appendf(out, "%-12s %8s %6s %12s %14s %12s %14s %14s %6s\n", "device", "rate Hz", "delay", "K N/m", "layer=1",
          "rendered/K", "generated uJ", "layer=2", "pass");
  for (const TaskLayerCheck& c : checks)
    appendf(out, "%-12s %8.0f %6d %12.4g %14s %12.3f %14.3g %14s %6s\n", c.device.c_str(), c.rate_hz, c.delay,
            c.stiffness, toString(c.layered.outcome), c.layered.rendered_stiffness / c.stiffness,
            1e6 * c.layered.generated_energy, toString(c.observed.outcome), c.pass() ? "yes" : "no");
  return out;
}

void writeCsv(const std::string& out, const std::vector<DeviceZWidth>& results,
              const std::vector<ZWidthDevice>& devices) {
  {
    tools::CsvWriter csv(out + "/devices.csv",
                         {"device", "joint", "responds", "b_identified", "coulomb_identified", "inertia_identified",
                          "identification_hz", "identification_amplitude", "resolution", "b_params", "coulomb_params"});
    for (std::size_t i = 0; i < results.size(); ++i) {
      const DeviceZWidth& r = results[i];
      const JointIdentification& id = r.identification;
      csv.row(r.name, {static_cast<double>(r.joint), id.responds ? 1.0 : 0.0, id.damping, id.coulomb, id.inertia,
                       id.frequency_hz, id.amplitude, r.resolution, devices[i].param_viscous, devices[i].param_coulomb});
    }
  }
  {
    // limiting: 0 Colgate-Brown, 1 Abbott-Okamura; below/above: the search's range was not enough.
    tools::CsvWriter csv(out + "/boundaries.csv",
                         {"device", "rate_hz", "delay", "wall_damping", "passivity", "k_max", "k_fail", "below_range",
                          "above_range", "k_colgate", "k_colgate_params", "k_quantization", "k_bound", "limiting",
                          "ratio_to_colgate", "runs", "b_identified", "coulomb_identified", "identification_hz"});
    for (const DeviceZWidth& r : results)
      for (const Boundary& b : r.boundaries)
        csv.row(r.name, {b.wall.rate_hz, static_cast<double>(b.wall.delay), b.wall.damping, b.wall.passivity ? 1.0 : 0.0,
                         b.k_max, b.k_fail, b.below_range ? 1.0 : 0.0, b.above_range ? 1.0 : 0.0, b.k_colgate,
                         b.k_colgate_params, b.k_quantization, b.k_bound, b.limiting == "Abbott-Okamura" ? 1.0 : 0.0,
                         b.k_colgate > 0.0 ? b.k_max / b.k_colgate : std::nan(""),
                         static_cast<double>(b.runs.size()), b.identification.damping, b.identification.coulomb,
                         b.identification.frequency_hz});
  }
  {
    // outcome: 0 passive, 1 active, 2 limit cycle, 3 divergent.
    tools::CsvWriter csv(out + "/runs.csv",
                         {"device", "rate_hz", "delay", "wall_damping", "passivity", "stiffness", "outcome",
                          "generated_energy", "tolerance", "wall_energy_out", "passivity_dissipated", "press_torque",
                          "max_penetration", "hold_amplitude", "hold_entries", "final_amplitude", "final_entries"});
    for (const DeviceZWidth& r : results)
      for (const Boundary& b : r.boundaries)
        for (const WallRun& run : b.runs)
          csv.row(r.name, {run.wall.rate_hz, static_cast<double>(run.wall.delay), run.wall.damping,
                           run.wall.passivity ? 1.0 : 0.0, run.stiffness, static_cast<double>(run.outcome),
                           run.generated_energy, run.tolerance, run.wall_energy_out, run.passivity_dissipated,
                           run.press_torque, run.max_penetration, run.hold_amplitude,
                           static_cast<double>(run.hold_entries), run.final_amplitude,
                           static_cast<double>(run.final_entries)});
  }
}

// The table at delay 0 and B = 0, and where the bound does not describe a joint, why (summary.txt).
std::string summaryText(const std::vector<DeviceZWidth>& results, const ZWidthOptions& options) {
  std::string out;
  appendf(out, "\n%-12s %4s %8s %12s %12s %7s %12s %12s %6s\n", "device", "joint", "rate Hz", "K_max meas", "K_max C-B",
              "ratio", "K_max A-O", "K_max PC", "gain");
  for (const DeviceZWidth& r : results) {
    if (!r.note.empty()) {
      appendf(out, "%-12s %4d  %s\n", r.name.c_str(), r.joint, r.note.c_str());
      continue;
    }
    for (const double rate : options.rates_hz) {
      const Boundary* off = findCase(r, rate, 0, false);
      const Boundary* on = findCase(r, rate, 0, true);
      if (!off && !on) {
        appendf(out, "%-12s %4d %8.0f  not simulated: faster than the plant's own integration step\n", r.name.c_str(),
                    r.joint, rate);
        continue;
      }
      const Boundary* any = off ? off : on;
      const double measured = off ? off->k_max : std::nan("");
      const double with_pc = on ? on->k_max : std::nan("");
      appendf(out, "%-12s %4d %8.0f %11.4g%s %12.4g %7.3f %12.4g %11.4g%s %6.2f\n", r.name.c_str(), r.joint, rate,
                  measured, off && off->above_range ? "+" : " ", any->k_colgate,
                  any->k_colgate > 0.0 ? measured / any->k_colgate : std::nan(""), any->k_quantization, with_pc,
                  on && on->above_range ? "+" : " ", with_pc / measured);
    }
  }
  appendf(out, "K in N m/rad (N/m for a prismatic joint); C-B: Colgate-Brown 2 b / T with b identified on the plant; "
              "A-O: Abbott-Okamura 2 f_c / step (inf: ideal sensor); PC: the passivity controller on; '+': passive up "
              "to the search's ceiling (a lower bound).\n");
  for (const DeviceZWidth& r : results) {
    if (r.note.empty() && !r.bound_applies)
      appendf(out, "%s: Colgate-Brown's bound does not describe joint %d: %s.\n", r.name.c_str(), r.joint,
              r.bound_note.c_str());
    if (!r.bound_applies) continue;
    for (const double rate : options.rates_hz) {
      const Boundary* off = findCase(r, rate, 0, false);
      if (off && !boundResolved(r, *off))
        appendf(out,
                "%s at %g Hz: not checked against the bound: the identification at the contact mode's %.0f Hz moved "
                "joint %d by %.1f sensor steps with 0.6 of its effort limit (b needs 10); the boundary there is set "
                "by the encoder's quantization.\n",
                r.name.c_str(), rate, off->identification.frequency_hz, r.joint,
                off->identification.amplitude / r.resolution);
    }
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Z-width of every registered device: the largest passive joint-space wall stiffness per servo rate, "
               "command delay and damping, with and without the passivity controller, beside the analytic bounds"};
  std::vector<std::string> device_choices = {"all", kMassDamper};
  for (const DeviceDefinition* d : deviceDefinitions()) device_choices.push_back(d->name);
  std::string device = "all";
  std::vector<double> rates = {500.0, 1000.0, 2000.0, 4000.0};
  std::vector<double> fractions = {0.25, 0.5, 0.75};
  int max_delay = 3;
  int joint = 0;
  std::string passivity = "both";
  double precision = 0.01;
  unsigned threads = 0;
  std::string out = "out/zwidth";
  std::string params = defaultParamsDirectory();
  std::string free_space = "on";
  std::string task = "on";
  app.footer("Exit status: 0 the sweep completed; 2 it could not complete; 101/105 a refused command-line value.");
  tools::CommandLine cli(app, "uhaptics-zwidth");
  cli.choice("--device", device, "device to sweep (all: every registered device and the 1-DoF mass-damper)",
             device_choices);
  cli.numbers("--rates", rates, 0, "servo rates [Hz]", 50.0, 20000.0);
  cli.integer("--max-delay", max_delay, "command delays 0..D servo periods", 0, kMaxZWidthDelay);
  cli.choice("--passivity", passivity, "with the passivity controller, without, or both", {"both", "on", "off"});
  cli.numbers("--damping-fractions", fractions, 0,
              "wall damping B as fractions of the joint's identified damping b (delay 0; B = 0 is always swept)", 0.0,
              0.99);
  cli.number("--precision", precision, "relative width at which the search for K_max stops", 0.001, 0.5);
  cli.integer("--joint", joint, "the actuated joint the wall acts on", 0, wire::kMaxChannels - 1);
  cli.integer("--threads", threads, "worker threads (0 = all cores)", 0, kMaxThreads);
  cli.choice("--free-space", free_space,
             "run each device's rendering policy in free space under the wall (on), or the bare plant (off)",
             {"on", "off"});
  cli.choice("--task", task,
             "also the task-space wall at the tool (on), not (off), or only it (only): task_boundaries.csv, "
             "stiffness.csv",
             {"on", "off", "only"});
  cli.outputFolder("--out", out, "output folder");
  cli.inputFolder("--params", params, "device parameter folder");
  if (const int status = cli.parse(argc, argv); status >= 0) return status;

  try {
    std::vector<ZWidthDevice> devices;
    if (device == "all" || device == kMassDamper) devices.push_back(massDamperDevice(MassDamperParams{}));
    for (const DeviceDefinition* d : deviceDefinitions())
      if (device == "all" || device == d->name) {
        devices.push_back(zwidthDevice(*d, params, joint));
        if (free_space == "off") devices.back().make_free_space = nullptr;
      }

    ZWidthOptions options;
    options.rates_hz = rates;
    options.delays.clear();
    for (int d = 0; d <= max_delay; ++d) options.delays.push_back(d);
    options.damping_fractions = fractions;
    options.with_passivity = passivity != "off";
    options.without_passivity = passivity != "on";
    options.relative_precision = precision;
    options.threads = threads;
    tools::ensureDirectory(out);  // after the devices are read: a refused file leaves no folder

    const bool joint_space = task != "only";
    std::vector<TaskZWidthDevice> task_devices;
    if (task != "off") {
      if (device == "all" || device == kMassDamper) task_devices.push_back(pointMassTaskDevice());
      for (const DeviceDefinition* d : deviceDefinitions())
        if (device == "all" || device == d->name) task_devices.push_back(taskZWidthDevice(*d, params));
    }
    TaskZWidthOptions task_options;
    task_options.rates_hz = rates;
    task_options.threads = threads;
    // The task wall at delay 0 (the simulation's) and 1 (the board protocol's), within --max-delay.
    task_options.delays = max_delay >= 1 ? std::vector<int>{0, 1} : std::vector<int>{0};

    std::size_t cases = joint_space ? zwidthCases(options, 1.0).size() * devices.size() : 0;
    for (const TaskZWidthDevice& d : task_devices)
      if (d.skip_note.empty())
        for (const std::string& renderer : d.renderers) {
          const bool native = std::find(d.native_rate_renderers.begin(), d.native_rate_renderers.end(), renderer) !=
                              d.native_rate_renderers.end();
          cases += (native ? 1 : task_options.rates_hz.size()) * task_options.delays.size();
        }
    tools::Progress progress("zwidth", cases);
    const auto t0 = std::chrono::steady_clock::now();
    const std::clock_t cpu0 = std::clock();
    std::vector<DeviceZWidth> results;
    if (joint_space) results = sweepZWidth(devices, options, [&] { progress.advance(); });
    std::vector<DeviceTaskZWidth> task_results;
    if (!task_devices.empty()) task_results = sweepTaskZWidth(task_devices, task_options, [&] { progress.advance(); });
    progress.finish();
    // The layer's check at the board's rate, where the sweep measured the spring without it.
    const std::vector<TaskLayerCheck> layer_checks =
        task_devices.empty() ? std::vector<TaskLayerCheck>{} : checkPassivityLayer(task_devices, task_results);
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const double cpu = static_cast<double>(std::clock() - cpu0) / CLOCKS_PER_SEC;

    std::size_t runs = 0, boundaries = 0;
    for (const DeviceZWidth& r : results) {
      boundaries += r.boundaries.size();
      for (const Boundary& b : r.boundaries) runs += b.runs.size();
    }
    for (const DeviceTaskZWidth& r : task_results) {
      boundaries += r.boundaries.size();
      for (const TaskBoundary& b : r.boundaries) runs += b.runs.size();
    }
    for (const DeviceZWidth& r : results) {
      if (!r.identification.responds) continue;
      std::printf("%-12s joint %d: inertia %.3g kg m^2, sensor step %.3g rad; b [N m s/rad], f_c [N m] at each "
                  "rate's contact frequency:",
                  r.name.c_str(), r.joint, r.identification.inertia, r.resolution);
      for (std::size_t i = 0; i < r.rate_identification.size(); ++i) {
        const JointIdentification& id = r.rate_identification[i];
        std::printf(" %g Hz: b %.4g f_c %.3g (%.0f Hz, %.2g rad);", options.rates_hz[i], id.damping, id.coulomb,
                    id.frequency_hz, id.amplitude);
      }
      std::printf("\n");
    }
    for (const DeviceTaskZWidth& r : task_results)
      if (r.note.empty())
        std::printf("%-12s task: mass along n %.3g kg, b_n %.4g N s/m at %.0f Hz (hand b_h %.3g N s/m), force "
                    "capacity along n %.3g N\n",
                    r.name.c_str(), r.identification.mass, r.identification.damping, r.identification.frequency_hz,
                    r.hand_damping, r.force_capacity);
    std::string summary = joint_space ? summaryText(results, options) : std::string();
    if (!task_results.empty()) summary += taskSummaryText(task_results) + layerCheckText(layer_checks);
    std::printf("%s", summary.c_str());
    std::printf("%zu boundaries, %zu runs; wall time %.1f s on %u threads, CPU %.1f s\n", boundaries, runs, wall,
                threads ? threads : hardwareThreads(), cpu);

    if (joint_space) writeCsv(out, results, devices);
    if (!task_results.empty()) writeTaskCsv(out, task_results);
    tools::runPlotScript("zwidth.py", {out});
    std::ofstream(out + "/summary.txt") << summary;
    ReproductionTable table = joint_space ? zwidthReproduction(results) : ReproductionTable{};
    if (!task_results.empty()) {
      const ReproductionTable task_table = taskZWidthReproduction(task_devices, task_results);
      for (const ReproductionRow& row : task_table.rows()) table.add(row);
      const ReproductionTable layer_table = passivityLayerReproduction(layer_checks);
      for (const ReproductionRow& row : layer_table.rows()) table.add(row);
    }
    table.writeCsv(out + "/reproduction.csv");
    std::printf("\n%s\n", table.format().c_str());
    return table.allPass() ? tools::CommandLine::kAllPass : tools::CommandLine::kRowsFail;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "uhaptics-zwidth: %s\n", e.what());
    return tools::CommandLine::kRunError;
  }
}
