#pragma once
// What a device session did, for logs and for tests that only see a process from outside (the
// drop-in test runs an unchanged CHAI3D example and reads this file afterwards). The servo thread
// records each tick (lock-free, allocation-free); any other thread may take a snapshot and write it.
#include <array>
#include <atomic>
#include <cstdint>
#include <string>

#include "uhaptics/backends/referee.hpp"
#include "uhaptics/backends/servo_timing.hpp"
#include "uhaptics/renderers/device_policy.hpp"

namespace uhaptics {

/// A figure of the device's own rendering method (e.g. the LQR wall's engagements, its deepest
/// penetration) or of the passivity layer around it: a count, a maximum or a latest value, named by
/// the device.
struct RendererFigure {
  using Kind = FigureKind;
  const char* name = "";  // a string literal of the device class: lives as long as the program
  Kind kind = Kind::kCount;
  double value = 0.0;
};

struct SessionStatsSnapshot {
  /// The TAU's ten figures plus the passivity layer's six, with room to spare.
  static constexpr int kMaxFigures = 20;
  std::uint64_t ticks = 0;          // servo ticks simulated / sent to the device
  double seconds = 0.0;             // wall time since start()
  double rate_hz = 0.0;             // ticks / seconds
  std::uint64_t contacts = 0;       // episodes with |commanded force| above the contact threshold
  std::uint64_t contact_ticks = 0;  // ticks spent in such an episode
  double peak_force = 0.0;          // [N] largest commanded (application) force
  double peak_output = 0.0;         // largest actuator command the device method produced (device units)
  std::uint64_t faults = 0;         // ticks that ended with a Fault (zero command sent)
  bool in_contact = false;          // the latest tick was inside a contact episode
  /// The board link (emulated, usb): ticks without a reading (zero sent), the episodes of them
  /// (a silent or unplugged board, a host watchdog trip, a stopped loop), and the episodes that
  /// ended with readings again. link_losses - link_recoveries is 1 while the link is down, else 0.
  std::uint64_t ticks_without_reading = 0;
  std::uint64_t link_losses = 0;
  std::uint64_t link_recoveries = 0;
  /// Board backends: servo ticks whose application input was stale (the efforts ramped to zero),
  /// and the episodes of them (the application's haptic thread stalled, or stopped sending).
  std::uint64_t stale_input_ticks = 0;
  std::uint64_t stale_input_episodes = 0;
  /// Box of the positions the device visited, in workspace radii around the workspace centre (what
  /// CHAI3D maps to world units when a tool's workspace radius is 1); empty (min > max) before a tick.
  std::array<double, 3> visited_min{{1.0, 1.0, 1.0}}, visited_max{{-1.0, -1.0, -1.0}};
  /// The device's renderer figures, in the order it declared them.
  std::array<RendererFigure, kMaxFigures> figures{};
  int figure_count = 0;
  /// The referee's figures from the simulated plant's truth (sim and emulated; referee.hpp), filled
  /// in by the device that has one: has_referee false on usb or with the option "referee" 0.
  bool has_referee = false;
  RefereeReport referee;
  /// The board's servo thread on the host (emulated, usb): its periods and how late it woke, so a
  /// session says when the thread that renders it was held up. has_servo_timing false on sim.
  bool has_servo_timing = false;
  TimingReport servo_timing;
  /// The figure named name, or nullptr.
  const RendererFigure* figure(const std::string& name) const noexcept;
};

class SessionStats final : public FigureRecorder {
 public:
  /// contact_threshold [N]: a contact starts above it and ends below half of it (hysteresis, so
  /// force ripple at the threshold is not counted as many contacts).
  explicit SessionStats(double contact_threshold = 0.05) noexcept : threshold_(contact_threshold) {}

  /// Resets the counters; wall_time [s] from any monotonic clock.
  void start(double wall_time) noexcept;
  /// One servo tick. Call from one thread only (the servo thread).
  void recordTick(double commanded_force, double output_magnitude, bool fault) noexcept;
  /// Whether this tick had a joint reading (servo thread, once per tick).
  void recordReading(bool have_reading) noexcept;
  /// Whether this tick's application input was stale (servo thread, once per tick with a reading).
  void recordInput(bool stale) noexcept;
  /// Where the device is after a tick, in workspace radii (non-finite values are ignored).
  void recordPosition(double x, double y, double z) noexcept;
  /// A command refused before any tick (e.g. non-finite): counted as a fault, not as a tick.
  void recordFault() noexcept { faults_.fetch_add(1, std::memory_order_relaxed); }
  SessionStatsSnapshot snapshot(double wall_time) const noexcept;

  /// Declares a renderer figure (set-up only, before the servo thread records; name a string
  /// literal) and returns its id for count()/observeMaximum(). start() zeroes the values and keeps
  /// the declarations. Throws uhaptics::Error past kMaxFigures or for a repeated name.
  int declareFigure(const char* name, FigureKind kind) override;
  /// Servo thread: adds n to a count / raises a maximum / sets a value (non-finite values are ignored).
  void count(int id, std::uint64_t n = 1) noexcept override;
  void observeMaximum(int id, double value) noexcept override;
  void setValue(int id, double value) noexcept override;

 private:
  double threshold_;
  bool in_contact_ = false;  // servo thread only
  std::atomic<bool> in_contact_now_{false};  // its copy for snapshots
  std::atomic<double> start_time_{0.0};
  std::atomic<std::uint64_t> ticks_{0};
  std::atomic<std::uint64_t> contacts_{0};
  std::atomic<std::uint64_t> contact_ticks_{0};
  std::atomic<std::uint64_t> faults_{0};
  bool link_down_ = false;  // servo thread only
  std::atomic<std::uint64_t> ticks_without_reading_{0}, link_losses_{0}, link_recoveries_{0};
  bool input_stale_ = false;  // servo thread only
  std::atomic<std::uint64_t> stale_input_ticks_{0}, stale_input_episodes_{0};
  std::atomic<double> peak_force_{0.0};
  std::atomic<double> peak_output_{0.0};
  std::array<std::atomic<double>, 3> visited_min_{}, visited_max_{};
  std::atomic<bool> visited_any_{false};
  std::array<RendererFigure, SessionStatsSnapshot::kMaxFigures> figures_{};  // names and kinds
  std::array<std::atomic<double>, SessionStatsSnapshot::kMaxFigures> figure_values_{};
  int figure_count_ = 0;
};

/// One JSON object: the snapshot plus the labels that say what ran; the renderer figures are the
/// object "renderer_figures", the referee's (when there is one) the object "referee" (NaN: null).
std::string formatStatsJson(const SessionStatsSnapshot& stats, const std::string& device,
                            const std::string& backend, const std::string& renderer);

/// Writes text to path via a temporary file and rename, so a reader never sees half a file even if
/// the process is killed mid-write. Throws uhaptics::Error when the file cannot be written.
void writeFileAtomically(const std::string& path, const std::string& text);

}  // namespace uhaptics
