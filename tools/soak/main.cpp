// uhaptics-soak: each device on the emulated board for a long real-time session, driven as a
// CHAI3D application drives it, with random board faults injected mid-contact (soak.hpp). Prints a
// progress line every 10 s and a summary per device; writes <out>/soak.csv (one row per device)
// and <out>/soak_faults.csv (one row per fault). Exit 1 when a device fails a criterion.
//
//   uhaptics-soak --minutes 10 --out out/soak            # every device, 10 min each
//   uhaptics-soak --device tau --minutes 10 --out out/soak
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>

#include "soak.hpp"
#include "uhaptics/chai3d/device_registry.hpp"
#include "uhaptics/tools/cli.hpp"
#include "uhaptics/tools/plot.hpp"

int main(int argc, char** argv) {
  namespace tools = uhaptics::tools;
  CLI::App app{"Soak: each device on the emulated board under random board faults"};
  app.footer("Exit status: 0 every device passes; 1 a device fails a criterion; 2 the run could not complete; "
             "101/105 a refused command-line value (conversion/validation).");
  tools::CommandLine cli(app, "uhaptics-soak");
  std::string device = "all", out = "out/soak";
  double minutes = 10.0, interval = 2.0;
  std::uint64_t seed = 1;
  std::uint64_t max_heap_growth = 65536;
  std::vector<std::string> devices = uhaptics::adapter::deviceNames();
  std::vector<std::string> choices = devices;
  choices.push_back("all");
  cli.choice("--device", device, "a device name or all", choices);
  cli.number("--minutes", minutes, "real time per device", 0.01, 10000.0);
  cli.number("--fault-interval", interval, "mean quiet time between faults [s]", 0.05, 600.0);
  cli.integer("--seed", seed, "random seed of the fault sequence", 0, std::numeric_limits<long long>::max());
  cli.integer("--max-heap-growth", max_heap_growth, "largest accepted heap growth after warm-up [bytes]", 0,
              1LL << 40);
  cli.outputFolder("--out", out, "folder of soak.csv and soak_faults.csv");
  if (const int status = cli.parse(argc, argv); status >= 0) return status;
  if (device != "all") devices = {device};
  try {
    tools::ensureDirectory(out);
  } catch (const std::exception& e) {
    std::cerr << "uhaptics-soak: --out: " << e.what() << "\n";
    return tools::CommandLine::kRunError;
  }

  std::vector<uhaptics::soak::Result> results;
  bool all_passed = true;
  for (const std::string& name : devices) {
    uhaptics::soak::Options options;
    options.device = name;
    options.seconds = 60.0 * minutes;
    options.seed = seed;
    options.mean_fault_interval = interval;
    double next_line = 0.0;
    const auto progress = [&](const uhaptics::soak::Result& r, double t) {
      if (t < next_line) return;
      next_line = t + 10.0;
      std::fprintf(stderr, "%s: %5.0f / %.0f s, %zu faults (%llu recovered), lost frames %llu, watchdog trips %llu, max command %.0f %% of limit\n",
                   name.c_str(), t, options.seconds, r.faults.size(), static_cast<unsigned long long>(r.recovered()),
                   static_cast<unsigned long long>(r.frames_lost), static_cast<unsigned long long>(r.host_watchdog_trips),
                   100.0 * r.max_command_ratio);
    };
    uhaptics::soak::Result r = uhaptics::soak::run(options, progress);
    const bool passed = r.passed(static_cast<long long>(max_heap_growth));
    all_passed = all_passed && passed;
    if (!r.error.empty()) {
      std::cout << name << ": " << r.error << "\n";
    } else {
      std::cout << name << ": " << r.seconds << " s, " << r.servo_ticks << " servo ticks, " << r.faults.size()
                << " faults injected, " << r.recovered() << " recovered (link), " << r.renderingNotResumed()
                << " with the device's rendering not resumed, " << r.zeroLate()
                << " not zeroed within " << r.watchdog_periods << " periods; lost frames " << r.frames_lost
                << ", rejected " << r.frames_rejected << ", host watchdog trips " << r.host_watchdog_trips
                << " (loop stalls " << r.loop_stalls << "), board watchdog trips " << r.board_watchdog_trips
                << ", max command " << 100.0 * r.max_command_ratio << " % of limit, heap growth "
                << r.heap_growth_bytes << " B, resident growth " << r.rss_growth_kib << " KiB: "
                << (passed ? "PASS" : "FAIL") << "\n";
    }
    results.push_back(std::move(r));
  }
  const auto write = [](const std::filesystem::path& path, const std::string& text) {
    std::ofstream f(path);
    f << text;
    f.close();
    if (!f) {
      std::cerr << "uhaptics-soak: cannot write " << path << "\n";
      return false;
    }
    return true;
  };
  if (!write(std::filesystem::path(out) / "soak.csv", uhaptics::soak::summaryCsv(results, static_cast<long long>(max_heap_growth))) ||
      !write(std::filesystem::path(out) / "soak_faults.csv", uhaptics::soak::faultsCsv(results)))
    return tools::CommandLine::kRunError;
  std::cout << "wrote " << out << "/soak.csv and " << out << "/soak_faults.csv\n";
  return all_passed ? tools::CommandLine::kAllPass : tools::CommandLine::kRowsFail;
}
