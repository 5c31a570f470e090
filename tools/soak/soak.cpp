#include "soak.hpp"

#include <malloc.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <random>
#include <sstream>
#include <thread>

#include "uhaptics/backends/board_catalog.hpp"
#include "uhaptics/backends/board_emulator.hpp"
#include "uhaptics/backends/device_definition.hpp"
#include "uhaptics/backends/params_location.hpp"
#include "uhaptics/backends/servo_loop.hpp"
#include "uhaptics/chai3d/device_registry.hpp"

namespace uhaptics::soak {
namespace {

using Clock = std::chrono::steady_clock;

long long heapInUseBytes() {
  const struct mallinfo2 m = mallinfo2();
  return static_cast<long long>(m.uordblks + m.hblkhd);
}

long long residentKib() {
  long pages = 0, resident = 0;
  std::FILE* f = std::fopen("/proc/self/statm", "r");
  if (f == nullptr) return 0;
  const int n = std::fscanf(f, "%ld %ld", &pages, &resident);
  std::fclose(f);
  return n == 2 ? static_cast<long long>(resident) * sysconf(_SC_PAGESIZE) / 1024 : 0;
}

// One fault from injection to recovery.
struct Episode {
  FaultRecord record;
  Clock::time_point end_wall{};       // when the fault itself is over (recovery is timed from here)
  std::uint64_t inject_tick = 0;      // the servo loop's tick count when it was injected
  std::uint64_t end_tick = 0;         // the fault's frames are spent once the loop passes this tick
  std::int64_t first_missing = -1;    // tick of the first period without a valid STATE
  bool ended = false, resumed = false;
  bool unplugged = false;
};

}  // namespace

const char* toString(FaultKind k) noexcept {
  switch (k) {
    case FaultKind::kSilent: return "silent";
    case FaultKind::kCorrupt: return "corrupt";
    case FaultKind::kDuplicate: return "duplicate";
    case FaultKind::kDelay: return "delay";
    case FaultKind::kUnplug: return "unplug";
    case FaultKind::kBoardReset: return "board-reset";
  }
  return "unknown";
}

std::uint64_t Result::recovered() const {
  return static_cast<std::uint64_t>(std::count_if(faults.begin(), faults.end(), [](const FaultRecord& f) { return f.recovered; }));
}

std::uint64_t Result::renderingNotResumed() const {
  return static_cast<std::uint64_t>(std::count_if(faults.begin(), faults.end(), [](const FaultRecord& f) { return !f.rendering_resumed; }));
}

std::uint64_t Result::zeroLate() const {
  const int limit = watchdog_periods;
  return static_cast<std::uint64_t>(std::count_if(faults.begin(), faults.end(), [limit](const FaultRecord& f) {
    return f.zero_expected && (!f.zeroed || f.periods_to_zero > limit);
  }));
}

bool Result::passed(long long max_heap_growth_bytes) const {
  return error.empty() && !faults.empty() && recovered() == faults.size() && renderingNotResumed() == 0 && zeroLate() == 0 &&
         max_command_ratio <= 1.0 + 1e-9 && heap_growth_bytes <= max_heap_growth_bytes;
}

Result run(const Options& options, const std::function<void(const Result&, double)>& progress) {
  Result result;
  result.device = options.device;
  auto control = std::make_shared<BoardEmulatorControl>();
  DeviceSelection selection;
  selection.device = options.device;
  selection.backend = "emulated";
  selection.joint_io.emulator_control = control;
  result.watchdog_periods = selection.joint_io.servo.watchdog_periods;
  chai3d::cUhapticsDevicePtr device;
  DeviceDescriptor descriptor;
  try {
    descriptor = boardSpec(findDevice(options.device), defaultParamsDirectory()).descriptor;
    device = adapter::createDevice(selection);
  } catch (const std::exception& e) {
    result.error = e.what();
    return result;
  }
  if (!device->open()) {
    result.error = "device '" + options.device + "' did not open on the emulated board (its message is above)";
    return result;
  }
  ServoLoop* loop = device->getServoLoop();  // the device's until close()
  // Room for every fault the run can hold: the records do not grow the heap while it is measured.
  result.faults.reserve(static_cast<std::size_t>(options.seconds / 0.25) + 16);

  std::mt19937_64 rng(options.seed);
  const auto uniform = [&rng](double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); };
  const auto integer = [&rng](int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); };
  const double amplitude = options.force_fraction * device->getSpecifications().m_maxLinearForce;  // a steady contact
  const int periods = result.watchdog_periods;

  const Clock::time_point start = Clock::now();
  const auto since = [&start](Clock::time_point t) { return std::chrono::duration<double>(t - start).count(); };
  Clock::time_point next_fault = start + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(options.warmup));
  Clock::time_point next_progress = start;
  bool have_baseline = false, active = false;
  long long heap0 = 0, rss0 = 0;
  Episode ep;
  const auto fillCounters = [&result, loop] {
    const ServoCounters k = loop->counters();
    result.servo_ticks = k.ticks;
    result.frames_lost = k.frames_lost;
    result.frames_rejected = k.frames_rejected;
    result.duplicates = k.duplicates;
    result.host_watchdog_trips = k.host_watchdog_trips;
    result.loop_stalls = k.loop_stalls;
    result.disconnects = k.disconnects;
    result.board_resets = k.board_resets;
  };

  for (Clock::time_point now = start; since(now) < options.seconds; now = Clock::now()) {
    const double t = since(now);
    // The application's haptic loop: read, then a force that turns slowly in the y-z plane.
    chai3d::cVector3d position;
    device->getPosition(position);
    const double phase = 2.0 * M_PI * t / 3.0;
    device->setForceAndTorqueAndGripperForce(chai3d::cVector3d(0.0, amplitude * std::cos(phase), -amplitude * std::sin(phase)),
                                             chai3d::cVector3d(0, 0, 0), 0.0);
    ++result.app_cycles;
    BoardEmulator::Snapshot board;
    if (control->snapshot(board)) {
      for (int i = 0; i < descriptor.actuators; ++i) {
        const double limit = descriptor.effort_limit[static_cast<std::size_t>(i)];
        if (limit > 0.0) result.max_command_ratio = std::max(result.max_command_ratio, std::abs(board.applied[static_cast<std::size_t>(i)]) / limit);
      }
    }
    ServoEvent e;
    while (loop->nextEvent(e)) {
      if (!active || e.tick <= ep.inject_tick) continue;
      FaultRecord& f = ep.record;
      switch (e.kind) {
        case ServoEventKind::kStateMissing:
          if (ep.first_missing < 0) ep.first_missing = static_cast<std::int64_t>(e.tick);
          break;
        case ServoEventKind::kHostWatchdog:
          if (!f.zeroed) {  // without a missing STATE before it: the loop itself stalled (zero at once)
            f.zeroed = true;
            f.periods_to_zero = ep.first_missing >= 0 ? static_cast<int>(static_cast<std::int64_t>(e.tick) - ep.first_missing + 1) : 0;
          }
          break;
        case ServoEventKind::kDisconnected:
        case ServoEventKind::kBoardReset:
          if (!f.zeroed) {
            f.zeroed = true;
            f.periods_to_zero = static_cast<int>(e.tick - ep.inject_tick);
          }
          break;
        case ServoEventKind::kResumed: ep.resumed = true; break;
        default: break;
      }
    }

    if (!have_baseline && t >= options.warmup) {
      heap0 = heapInUseBytes();
      rss0 = residentKib();
      have_baseline = true;
    }

    if (!active && now >= next_fault) {
      // Inject the next fault.
      ep = Episode{};
      FaultRecord& f = ep.record;
      f.kind = static_cast<FaultKind>(integer(0, 5));
      f.injected_at = t;
      ep.inject_tick = loop->counters().ticks;
      switch (f.kind) {
        case FaultKind::kSilent:
        case FaultKind::kCorrupt:
          f.frames = integer(1, 400);
          f.zero_expected = f.frames >= periods;
          control->inject(f.kind == FaultKind::kSilent ? BoardEmulator::Fault::kDrop : BoardEmulator::Fault::kCorrupt, f.frames);
          ep.end_tick = ep.inject_tick + static_cast<std::uint64_t>(f.frames) + 2;
          break;
        case FaultKind::kDuplicate:
          f.frames = integer(1, 50);
          control->inject(BoardEmulator::Fault::kDuplicate, f.frames);
          ep.end_tick = ep.inject_tick + static_cast<std::uint64_t>(f.frames) + 2;
          break;
        case FaultKind::kDelay:
          f.frames = integer(1, 3);
          f.delay_periods = integer(1, 10);
          // The held STATE arrives delay_periods later: delay_periods - 1 periods without one.
          f.zero_expected = f.delay_periods > periods;
          control->inject(BoardEmulator::Fault::kDelay, f.frames, f.delay_periods);
          ep.end_tick = ep.inject_tick + static_cast<std::uint64_t>(f.frames * (f.delay_periods + 1)) + 2;
          break;
        case FaultKind::kUnplug:
          f.frames = integer(20, 500);  // ms unplugged
          f.zero_expected = true;
          control->unplug();
          ep.unplugged = true;
          ep.end_wall = now + std::chrono::milliseconds(f.frames);
          break;
        case FaultKind::kBoardReset:
          f.zero_expected = true;
          control->resetBoard();
          ep.ended = true;
          ep.end_wall = now;
          break;
      }
      active = true;
    } else if (active) {
      FaultRecord& f = ep.record;
      if (!ep.ended) {
        if (ep.unplugged ? now >= ep.end_wall : loop->counters().ticks > ep.end_tick) {
          if (ep.unplugged) control->replug();
          ep.ended = true;
          ep.end_wall = now;
        }
      } else {
        const bool link = device->getLinkStatus() == LinkStatus::kRunning;
        const bool rendering = device->getLastFault() == Fault::kNone;
        const bool forces = control->snapshot(board) && board.outputs_enabled;
        const double waited = std::chrono::duration<double>(now - ep.end_wall).count();
        f.last_link = toString(device->getLinkStatus());  // what an unrecovered fault ended in
        f.last_fault = toString(device->getLastFault());
        f.board_applying = forces;
        const bool link_back = link && forces && (!f.zeroed || ep.resumed);
        if (link_back && !f.recovered) {
          f.recovered = true;
          f.recovery_s = waited;
        }
        f.rendering_resumed = link_back && rendering;
        if (f.rendering_resumed || waited > options.recovery_timeout) {
          result.faults.push_back(f);
          active = false;
          next_fault = now + std::chrono::duration_cast<Clock::duration>(
                                 std::chrono::duration<double>(uniform(0.5, 1.5) * options.mean_fault_interval));
        }
      }
    }

    if (progress && now >= next_progress) {
      result.seconds = t;
      fillCounters();
      progress(result, t);
      next_progress = now + std::chrono::seconds(1);
    }
    std::this_thread::sleep_for(std::chrono::microseconds(900));
  }
  if (active) {  // the run ended mid-fault: restore the board, the fault is not counted
    if (ep.unplugged && !ep.ended) control->replug();
  }
  result.seconds = since(Clock::now());
  if (have_baseline) {
    result.heap_growth_bytes = heapInUseBytes() - heap0;
    result.rss_growth_kib = residentKib() - rss0;
  }
  fillCounters();
  BoardEmulator::Snapshot board;
  if (control->snapshot(board)) result.board_watchdog_trips = board.watchdog_trips;
  const SessionStatsSnapshot stats = device->getSessionStats();
  result.device_link_losses = stats.link_losses;
  result.device_link_recoveries = stats.link_recoveries;
  device->close();
  return result;
}

std::string summaryCsv(const std::vector<Result>& results, long long max_heap_growth_bytes) {
  std::ostringstream out;
  out << "device,seconds,servo_ticks,faults,recovered,rendering_not_resumed,zero_late,frames_lost,frames_rejected,duplicates,"
         "host_watchdog_trips,loop_stalls,disconnects,board_resets,board_watchdog_trips,device_link_losses,"
         "device_link_recoveries,max_command_ratio,heap_growth_bytes,rss_growth_kib,pass,error\n";
  for (const Result& r : results) {
    out << r.device << ',' << r.seconds << ',' << r.servo_ticks << ',' << r.faults.size() << ',' << r.recovered() << ','
        << r.renderingNotResumed() << ',' << r.zeroLate() << ',' << r.frames_lost << ',' << r.frames_rejected << ',' << r.duplicates << ','
        << r.host_watchdog_trips << ',' << r.loop_stalls << ',' << r.disconnects << ',' << r.board_resets << ','
        << r.board_watchdog_trips << ',' << r.device_link_losses << ',' << r.device_link_recoveries << ','
        << r.max_command_ratio << ',' << r.heap_growth_bytes << ',' << r.rss_growth_kib << ','
        << (r.passed(max_heap_growth_bytes) ? "PASS" : "FAIL") << ",\"";
    for (const char c : r.error) out << (c == '"' ? '\'' : c);
    out << "\"\n";
  }
  return out.str();
}

std::string faultsCsv(const std::vector<Result>& results) {
  std::ostringstream out;
  out << "device,index,kind,frames_or_ms,delay_periods,injected_at_s,zero_expected,zeroed,periods_to_zero,recovered,recovery_ms,"
         "rendering_resumed,last_link,last_fault,board_applying\n";
  for (const Result& r : results) {
    for (std::size_t i = 0; i < r.faults.size(); ++i) {
      const FaultRecord& f = r.faults[i];
      out << r.device << ',' << i << ',' << toString(f.kind) << ',' << f.frames << ',' << f.delay_periods << ','
          << f.injected_at << ',' << f.zero_expected << ',' << f.zeroed << ',' << f.periods_to_zero << ','
          << f.recovered << ',' << 1e3 * f.recovery_s << ',' << f.rendering_resumed << ",\"" << f.last_link << "\",\"" << f.last_fault << "\","
          << f.board_applying << '\n';
    }
  }
  return out.str();
}

}  // namespace uhaptics::soak
