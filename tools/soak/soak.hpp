#pragma once
// A device on the emulated board, driven as a CHAI3D application drives it (the haptic loop reads
// the position and sets a force about once a millisecond, in real time), while board faults are
// injected at random through the joint-I/O options' BoardEmulatorControl: a silent board, corrupt,
// duplicated or delayed frames, an unplugged cable, a board reboot. Each fault is injected after
// the previous one has recovered, so what the device did can be attributed to it.
//
// Per fault it records whether the host watchdog (or the unplug) brought the command to zero
// within the loop's stated periods and whether the device recovered (the CHAI3D device reports a
// running link, no fault, and the board applies commands again); over the run, lost frames,
// watchdog trips, the largest effort the board applied (against its limit) and heap and resident
// memory growth after warm-up.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace uhaptics::soak {

struct Options {
  std::string device;               // a registered device name
  double seconds = 600.0;           // real time
  std::uint64_t seed = 1;
  double mean_fault_interval = 2.0; // [s] quiet time between a recovery and the next fault (mean)
  double recovery_timeout = 5.0;    // [s] a fault not recovered by then counts as unrecovered
  double warmup = 2.0;              // [s] before the memory baseline is taken
  double force_fraction = 0.1;      // the application's force, of the device's rated force
};

enum class FaultKind { kSilent, kCorrupt, kDuplicate, kDelay, kUnplug, kBoardReset };
const char* toString(FaultKind k) noexcept;

struct FaultRecord {
  FaultKind kind = FaultKind::kSilent;
  int frames = 0;             // silent/corrupt/duplicate/delay: frames affected; unplug: ms unplugged
  int delay_periods = 0;      // delay only
  double injected_at = 0.0;   // [s] since the session opened
  bool zero_expected = false; // the fault must bring the command to zero (watchdog, unplug, reset)
  bool zeroed = false;        // the loop reported zero (host watchdog, disconnect, board reset)
  int periods_to_zero = -1;   // servo periods from the first period without a valid STATE to zero
  bool recovered = false;          // the link is back: running, the board applying commands
  bool rendering_resumed = false;  // and the device's renderer works again (no fault)
  double recovery_s = 0.0;    // [s] from the end of the fault to a running link and forces again
  // The device's state when the record closed (what an unrecovered fault was stuck in).
  const char* last_link = "";
  const char* last_fault = "";
  bool board_applying = false;
};

struct Result {
  std::string device;
  std::string error;          // set when the device could not be opened
  double seconds = 0.0;
  int watchdog_periods = 0;
  std::vector<FaultRecord> faults;
  std::uint64_t servo_ticks = 0, frames_lost = 0, frames_rejected = 0, duplicates = 0, host_watchdog_trips = 0,
                loop_stalls = 0, disconnects = 0, board_resets = 0, board_watchdog_trips = 0, app_cycles = 0;
  std::uint64_t device_link_losses = 0, device_link_recoveries = 0;  // the CHAI3D device's statistics
  double max_command_ratio = 0.0;   // largest |applied effort| / limit over actuators and time
  long long heap_growth_bytes = 0;  // heap in use at the end minus after warm-up (glibc mallinfo2)
  long long rss_growth_kib = 0;     // resident set likewise
  std::uint64_t recovered() const;
  std::uint64_t renderingNotResumed() const;  // recovered links whose device still faulted at the timeout
  std::uint64_t zeroLate() const;   // faults that had to zero and did not within the watchdog's periods
  /// The criteria: opened, every fault recovered and zeroed in time, commands within limits, no
  /// heap growth beyond max_heap_growth_bytes.
  bool passed(long long max_heap_growth_bytes) const;
};

/// Runs one device; progress(result so far, elapsed s) is called about once a second.
Result run(const Options& options, const std::function<void(const Result&, double)>& progress = {});

/// CSV rows (with header lines) for a set of results: one row per device, one per fault.
std::string summaryCsv(const std::vector<Result>& results, long long max_heap_growth_bytes);
std::string faultsCsv(const std::vector<Result>& results);

}  // namespace uhaptics::soak
