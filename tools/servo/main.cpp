// uhaptics-servo: runs the real-time servo loop against a device's board — the in-process emulator
// (default) or real hardware over USB (--usb) — and reports timing (period and wake-up latency
// percentiles, overruns), link counters and events. Writes timing_histogram.csv, events.txt,
// summary.txt and timing.png into --out.
//
//   uhaptics-servo --device tau --seconds 5 --out out/servo          # emulator
//   uhaptics-servo --device tau --usb --params devices/params/tau.json # a plugged-in TAU board
//
// With hardware the commanded efforts are a gentle sinusoid at 10 % of each actuator's limit
// (--amplitude): hold the device, or use --amplitude 0 to only read.
#include <CLI/CLI.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <thread>
#include <vector>

#include "uhaptics/backends/board_catalog.hpp"
#include "uhaptics/backends/board_emulator.hpp"
#include "uhaptics/backends/device_plants.hpp"
#include "uhaptics/backends/libusb_transport.hpp"
#include "uhaptics/backends/servo_loop.hpp"
#include "uhaptics/core/fault.hpp"
#include "uhaptics/tools/csv.hpp"
#include "uhaptics/tools/plot.hpp"
#include "uhaptics/tools/reproduction.hpp"

using namespace uhaptics;

int main(int argc, char** argv) {
  CLI::App app{"Run the servo loop on a device's board (emulated or USB) and report its timing"};
  std::string device_name = "tau", params, out = "out/servo";
  double rate = 0.0, seconds = 3.0, amplitude = 0.1;
  bool usb = false, realtime = true;
  int watchdog_periods = 3;
  app.add_option("--device", device_name, "exo, tau or rhi")->check(CLI::IsMember({"exo", "tau", "rhi"}));
  app.add_option("--rate", rate, "servo rate in Hz, 500..10000 (default: the device's)");
  app.add_option("--seconds", seconds, "run time")->check(CLI::Range(0.1, 600.0));
  app.add_option("--amplitude", amplitude, "commanded sinusoid, fraction of each effort limit")->check(CLI::Range(0.0, 1.0));
  app.add_option("--watchdog-periods", watchdog_periods, "host watchdog")->check(CLI::Range(1, 1000));
  app.add_flag("--usb", usb, "talk to a real board over libusb instead of the emulator");
  app.add_option("--params", params, "device parameter file whose \"usb\" section gives the USB ids");
  app.add_flag("!--no-realtime", realtime, "do not try SCHED_FIFO");
  app.add_option("--out", out, "output folder");
  CLI11_PARSE(app, argc, argv);

  try {
    const wire::DeviceType type = deviceTypeFromName(device_name);
    const BoardSpec spec = params.empty() ? boardSpec(type, UHAPTICS_PARAMS_DIR) : boardSpecFromFile(type, params);
    const DeviceDescriptor& device = spec.descriptor;
    ServoConfig cfg;
    cfg.rate_hz = rate > 0.0 ? rate : spec.servo_rate_hz;
    cfg.board_watchdog_us = spec.board_watchdog_us;
    cfg.realtime = realtime;
    cfg.watchdog_periods = watchdog_periods;

    // The emulated board drives the device's own simulation; the hardware path needs no plant.
    std::unique_ptr<BoardPlant> plant;
    std::unique_ptr<Transport> transport;
    if (usb) {
      transport = std::make_unique<LibusbTransport>(device);
    } else {
      plant = makeDevicePlant(type, UHAPTICS_PARAMS_DIR);
      BoardEmulator::Config board;
      board.device = device.type;
      board.sample_rate_hz = spec.sample_rate_hz;
      board.effort_limit = device.effort_limit;
      transport = std::make_unique<BoardEmulator>(board, *plant);
    }
    ServoLoop loop(device, *transport, cfg);
    const wire::DeviceInfo info = loop.connect();
    std::printf("connected: %s on %s, protocol %u, firmware 0x%08x, %u joints, %u actuators, sampling %u Hz\n",
                device.name.c_str(), transport->describe(), info.selected_version, info.firmware_version,
                info.joint_count, info.actuator_count, info.sample_rate_hz);
    std::printf("%s\n", loop.start().c_str());

    tools::ensureDirectory(out);
    std::ofstream events(out + "/events.txt");
    const auto t0 = std::chrono::steady_clock::now();
    for (;;) {
      const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      if (t >= seconds) break;
      EffortRequest r;
      r.count = device.actuators;
      for (int i = 0; i < device.actuators; ++i)
        r.effort[i] = amplitude * device.effort_limit[i] * std::sin(2.0 * M_PI * 1.0 * t + i);
      loop.request(r);
      ServoEvent e;
      while (loop.nextEvent(e)) events << describe(e) << "\n";
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    loop.stop();
    ServoEvent e;
    while (loop.nextEvent(e)) events << describe(e) << "\n";

    const std::string summary = loop.summary();
    std::cout << summary << "\n";
    std::ofstream(out + "/summary.txt") << summary << "\n";
    std::vector<std::uint32_t> period(TimingStats::kBins), latency(TimingStats::kBins);
    loop.timingStats().histograms(period.data(), latency.data());
    {
      tools::CsvWriter csv(out + "/timing_histogram.csv", {"bin_us", "period_count", "wake_latency_count"});
      for (int b = 0; b < TimingStats::kBins; ++b)
        if (period[b] != 0 || latency[b] != 0)
          csv.row({static_cast<double>(b), static_cast<double>(period[b]), static_cast<double>(latency[b])});
    }
    const TimingReport timing = loop.timing();
    const ServoCounters k = loop.counters();
    tools::ReproductionTable table;
    table.addBound("hw", "frames lost", static_cast<double>(k.frames_lost), "= 0", k.frames_lost == 0, "frames");
    table.addBound("hw", "frames rejected", static_cast<double>(k.frames_rejected), "= 0", k.frames_rejected == 0, "frames");
    table.addBound("hw", "host watchdog trips", static_cast<double>(k.host_watchdog_trips), "= 0 (informative on a loaded machine)",
                   k.host_watchdog_trips == 0, "");
    table.addBound("hw", "wake latency p99", timing.wake_latency.p99_us, "informative", true, "us");
    table.addBound("hw", "period p99", timing.period.p99_us, "informative", true, "us");
    table.writeCsv(out + "/reproduction.csv");
    std::cout << table.format();
    char title[160];
    std::snprintf(title, sizeof title, "%s servo loop at %.0f Hz (%s)", device.name.c_str(), cfg.rate_hz,
                  usb ? "USB" : "emulated board");
    tools::runPlotScript("servo_timing.py", {out + "/timing_histogram.csv", out + "/timing.png", title,
                                             std::to_string(1e6 / cfg.rate_hz)});
    return k.frames_lost == 0 && k.frames_rejected == 0 ? 0 : 1;
  } catch (const Error& e) {
    std::cerr << "uhaptics-servo: " << e.what() << "\n";
    return 1;
  }
}
