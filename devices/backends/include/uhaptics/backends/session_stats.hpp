#pragma once
// What a device session did, for logs and for tests that only see a process from outside (the
// drop-in test runs an unchanged CHAI3D example and reads this file afterwards). The servo thread
// records each tick (lock-free, allocation-free); any other thread may take a snapshot and write it.
#include <atomic>
#include <cstdint>
#include <string>

namespace uhaptics {

struct SessionStatsSnapshot {
  std::uint64_t ticks = 0;          // servo ticks simulated / sent to the device
  double seconds = 0.0;             // wall time since start()
  double rate_hz = 0.0;             // ticks / seconds
  std::uint64_t contacts = 0;       // episodes with |commanded force| above the contact threshold
  std::uint64_t contact_ticks = 0;  // ticks spent in such an episode
  double peak_force = 0.0;          // [N] largest commanded (application) force
  double peak_output = 0.0;         // largest actuator command the device method produced (device units)
  std::uint64_t faults = 0;         // ticks that ended with a Fault (zero command sent)
};

class SessionStats {
 public:
  /// contact_threshold [N]: a contact starts above it and ends below half of it (hysteresis, so
  /// force ripple at the threshold is not counted as many contacts).
  explicit SessionStats(double contact_threshold = 0.05) noexcept : threshold_(contact_threshold) {}

  /// Resets the counters; wall_time [s] from any monotonic clock.
  void start(double wall_time) noexcept;
  /// One servo tick. Call from one thread only (the servo thread).
  void recordTick(double commanded_force, double output_magnitude, bool fault) noexcept;
  /// A command refused before any tick (e.g. non-finite): counted as a fault, not as a tick.
  void recordFault() noexcept { faults_.fetch_add(1, std::memory_order_relaxed); }
  SessionStatsSnapshot snapshot(double wall_time) const noexcept;

 private:
  double threshold_;
  bool in_contact_ = false;  // servo thread only
  std::atomic<double> start_time_{0.0};
  std::atomic<std::uint64_t> ticks_{0};
  std::atomic<std::uint64_t> contacts_{0};
  std::atomic<std::uint64_t> contact_ticks_{0};
  std::atomic<std::uint64_t> faults_{0};
  std::atomic<double> peak_force_{0.0};
  std::atomic<double> peak_output_{0.0};
};

/// One JSON object: the snapshot plus the labels that say what ran.
std::string formatStatsJson(const SessionStatsSnapshot& stats, const std::string& device,
                            const std::string& backend, const std::string& renderer);

/// Writes text to path via a temporary file and rename, so a reader never sees half a file even if
/// the process is killed mid-write. Throws uhaptics::Error when the file cannot be written.
void writeFileAtomically(const std::string& path, const std::string& text);

}  // namespace uhaptics
