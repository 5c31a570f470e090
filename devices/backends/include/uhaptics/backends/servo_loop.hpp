#pragma once
// The host's real-time servo loop for a device on a Transport (USB board or emulator).
//
// One dedicated thread wakes at absolute deadlines (clock_nanosleep(TIMER_ABSTIME) on
// CLOCK_MONOTONIC, SCHED_FIFO when permitted) and each period:
//   1. receives the board's STATE (the answer to the previous COMMAND), drains stale extras,
//      rejects malformed frames (counted per reason) and detects lost/duplicated frames by sequence;
//   2. computes the next command: the ServoRenderer if one is set, else the graphics thread's
//      latest effort request;
//   3. enforces safety: non-finite -> all zero, out-of-limit -> scaled into the limit box (direction
//      kept), the reason logged; host watchdog (no valid STATE for watchdog_periods periods, or the
//      loop itself stalled that long) -> zero;
//   4. sends COMMAND, publishes a snapshot for the graphics thread.
// Board resets and unplug/replug are handled in the loop: report, command zero, handshake, resume.
//
// Nothing on the periodic path allocates, locks or throws. The graphics thread talks to it through
// wait-free triple buffers and drains events (clamp reasons, faults) from a wait-free ring.
#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <thread>

#include "uhaptics/protocol/device_descriptor.hpp"
#include "uhaptics/backends/lockfree.hpp"
#include "uhaptics/backends/servo_timing.hpp"
#include "uhaptics/protocol/transport.hpp"
#include "uhaptics/protocol/wire_protocol.hpp"

namespace uhaptics {

struct ServoConfig {
  double rate_hz = 1000.0;            // 500 .. 10000
  int watchdog_periods = 3;           // host watchdog: periods without a valid STATE before zero
  std::uint32_t board_watchdog_us = 0;  // board watchdog; 0 = max(5 periods, 5 ms)
  int receive_timeout_us = 0;         // wait for STATE each period; 0 = half a period
  bool realtime = true;               // try SCHED_FIFO (needs CAP_SYS_NICE or an rtprio limit)
  /// SCHED_FIFO priority. CHAI3D's haptic thread asks for 99 on Linux: the servo loop asks the
  /// same, the highest SCHED_FIFO has (equal priorities do not preempt each other; on a machine
  /// with two or more cores both run).
  int realtime_priority = 99;
  /// With realtime: lock the process's current pages (mlockall(MCL_CURRENT)) so the servo thread
  /// never waits on a page fault. Not MCL_FUTURE: an application past its memlock limit would then
  /// fail its own allocations.
  bool lock_memory = true;
  /// Shift the loop's deadlines until each COMMAND reaches the board half a sample period after the
  /// board's newest sample (STATE: board_time_us minus sample_time_us). A board that samples on its
  /// own clock then always answers with the sample taken just before the previous COMMAND, so the
  /// command delay is kCommandDelayPeriods in every session, with half a period of margin for
  /// jitter on either side, instead of depending on the phase between the two clocks. A board whose
  /// sample age does not follow the shifts (one that samples when a COMMAND arrives) is left alone
  /// after kPhaseLockGiveUpPeriods of full-rate shifting, until the next handshake.
  bool phase_lock = true;
  int reconnect_interval_ms = 100;    // while unplugged: how often to look for the device
  int handshake_timeout_ms = 500;     // connect(): how long to wait for each handshake answer
  void validate() const;              // throws Error
};

/// kStopped: stop() ended the servo thread; nothing is sent or received any more (the last
/// snapshot says so instead of holding the last reading).
enum class LinkState : std::uint8_t { kConnecting, kRunning, kDisconnected, kStopped };

/// Servo -> graphics: the newest device state and what was sent.
struct DeviceSnapshot {
  std::uint64_t tick = 0;
  LinkState link = LinkState::kConnecting;
  bool host_watchdog_tripped = false;
  std::uint8_t board_status = 0;
  wire::BoardError board_error = wire::BoardError::kNone;
  std::uint32_t board_time_us = 0;
  int joints = 0;
  std::array<double, wire::kMaxChannels> position{};
  std::array<std::uint32_t, wire::kMaxChannels> sample_time_us{};
  int actuators = 0;
  std::array<double, wire::kMaxChannels> command_sent{};
};

/// Graphics -> servo: the efforts the application wants (checked before they leave the host).
struct EffortRequest {
  int count = 0;
  std::array<double, wire::kMaxChannels> effort{};
};

/// Optional servo-rate controller run in the servo thread (e.g. a uhaptics renderer).
class ServoRenderer {
 public:
  virtual ~ServoRenderer() = default;
  /// Writes `actuators` efforts. Must not allocate, block or throw; anything it writes is checked.
  virtual void render(const DeviceSnapshot& state, const EffortRequest& request, double* efforts) noexcept = 0;
  /// A period in which render() was not called: no valid STATE arrived (a late frame holds the
  /// previous command), the host watchdog holds the device at zero, or the board is disconnected or
  /// reconnecting (state.link, state.host_watchdog_tripped say which). Same rules as render().
  virtual void noReading(const DeviceSnapshot& state) noexcept { (void)state; }
};

enum class ServoEventKind : std::uint8_t {
  kFrameRejected,      // detail: wire::Reject
  kStateMissing,       // no valid STATE this period (first of a run)
  kFramesLost,         // value: frames missing from the board's sequence
  kDuplicateFrame,
  kBoardError,         // detail: wire::BoardError (reported when it changes)
  kHostWatchdog,       // zero commanded; value: periods without a valid STATE
  kLoopStalled,        // the servo thread itself woke late by >= watchdog periods; value: periods
  kResumed,            // valid STATEs again, commands resume
  kClamped,            // detail: channel, value: the requested effort (scaled into the limit box)
  kNonFiniteCommand,   // detail: channel; the whole command was zeroed
  kDisconnected,
  kReconnected,
  kBoardReset,         // board lost its configuration (reboot): handshake again
  kSendFailed,         // detail: TransportStatus
};
const char* toString(ServoEventKind k) noexcept;

struct ServoEvent {
  std::uint64_t tick = 0;
  ServoEventKind kind = ServoEventKind::kResumed;
  std::uint8_t detail = 0;
  double value = 0.0;
};
std::string describe(const ServoEvent& e);

struct ServoCounters {
  std::uint64_t ticks = 0, states = 0, states_missing = 0, frames_lost = 0, duplicates = 0,
                frames_rejected = 0, host_watchdog_trips = 0, loop_stalls = 0, clamped_ticks = 0,
                non_finite_commands = 0, disconnects = 0, reconnects = 0, board_resets = 0,
                send_failures = 0, events_dropped = 0;
  std::array<std::uint64_t, wire::kRejectReasons> rejected_by_reason{};
};

/// Result of the safety stage (exposed for tests).
struct SafetyOutcome {
  bool non_finite = false;
  std::uint32_t exceeded_mask = 0;   // channels that were beyond their limit
  double scale = 1.0;                // factor applied to bring the command into the box
};
/// Makes efforts[0..n) finite and within +-limits[i] (uses core limits.hpp).
SafetyOutcome enforceEffortLimits(double* efforts, int n, const double* limits) noexcept;

class ServoLoop {
 public:
  /// Keeps references to transport and renderer (both must outlive the loop). Throws Error when the
  /// descriptor or the configuration is invalid (DeviceDescriptor::validate, ServoConfig::validate).
  ServoLoop(const DeviceDescriptor& device, Transport& transport, const ServoConfig& config,
            ServoRenderer* renderer = nullptr);
  /// Periods between the reading a command is computed from and the period the command acts in:
  /// the STATE a period reads answers the previous period's COMMAND (request/answer cycle), so the
  /// reading is one exchange old when the command leaves.
  static constexpr int kCommandDelayPeriods = 1;
  /// Consecutive periods the phase lock may shift at its slew limit (2 % of a period) before it
  /// concludes the board's sample age does not depend on the host's phase: a free-running board is
  /// locked within 25 such periods (half a sample period at 2 % each).
  static constexpr int kPhaseLockGiveUpPeriods = 200;
  ~ServoLoop();
  ServoLoop(const ServoLoop&) = delete;
  ServoLoop& operator=(const ServoLoop&) = delete;

  /// Handshake from the calling thread. Throws Error with an actionable message: no answer,
  /// protocol version mismatch, wrong device type or channel counts, configuration refused.
  wire::DeviceInfo connect();
  /// Starts the servo thread (after connect()). Returns a note on real-time scheduling.
  std::string start();
  /// Stops the thread after commanding zero; the last snapshot then reports LinkState::kStopped.
  /// Idempotent.
  void stop();
  bool running() const noexcept { return running_.load(std::memory_order_acquire); }

  // Graphics side (one thread).
  void request(const EffortRequest& r) noexcept { requests_.write(r); }
  bool latest(DeviceSnapshot& out) noexcept { return snapshots_.read(out); }
  bool nextEvent(ServoEvent& out) noexcept { return events_.pop(out); }

  // Any thread.
  ServoCounters counters() const noexcept;
  TimingReport timing() const { return timing_.report(); }
  const TimingStats& timingStats() const noexcept { return timing_; }
  std::string realtimeNote() const;
  /// How old the board's newest sample was when a COMMAND reached it [us], averaged over about the
  /// last 50 STATEs: what the phase lock steers to half the board's sample period. 0 before the
  /// first STATE.
  double sampleAgeUs() const noexcept { return sample_age_us_.load(std::memory_order_relaxed); }
  /// Counters, timing and real-time note as text (what stop() leaves for the log).
  std::string summary() const;

  /// One period's work without the thread and sleep (tests drive it directly). Allocation-free.
  void tick() noexcept;

 private:
  enum class HandshakeResult { kOk, kNoAnswer, kDisconnected, kVersionMismatch, kWrongDevice, kRefused };
  HandshakeResult handshake(int timeout_us, wire::DeviceInfo& info) noexcept;
  bool awaitFrame(wire::MessageType type, int timeout_us, wire::Frame& out, TransportStatus& status) noexcept;
  bool sendFrame(wire::Frame& frame) noexcept;
  void sendZero() noexcept;
  void run() noexcept;
  void runningTick() noexcept;
  void computeCommand(bool fresh) noexcept;
  /// After a fresh STATE: the sample's age and, with config_.phase_lock, the deadline shift.
  void lockPhase() noexcept;
  void tripWatchdog(ServoEventKind why, double periods) noexcept;
  void onDisconnected() noexcept;
  /// The state part of a snapshot (what the renderer sees and what the graphics thread gets).
  void fillSnapshot(DeviceSnapshot& s) const noexcept;
  void publish() noexcept;
  void emit(ServoEventKind kind, std::uint8_t detail = 0, double value = 0.0) noexcept;
  void bump(std::atomic<std::uint64_t>& c, std::uint64_t n = 1) noexcept {
    c.store(c.load(std::memory_order_relaxed) + n, std::memory_order_relaxed);  // single writer
  }

  const DeviceDescriptor device_;
  Transport& transport_;
  const ServoConfig config_;
  ServoRenderer* const renderer_;
  const std::int64_t period_ns_;
  const int receive_timeout_us_;
  const std::uint32_t board_watchdog_us_;

  std::thread thread_;
  std::atomic<bool> running_{false};
  std::atomic<int> realtime_state_{0};  // 0 not requested, 1 SCHED_FIFO, else errno of the refusal
  std::atomic<int> memory_state_{0};    // 0 not requested, 1 locked, else errno of the refusal
  TimingStats timing_;

  TripleBuffer<EffortRequest> requests_;
  TripleBuffer<DeviceSnapshot> snapshots_;
  SpscRing<ServoEvent, 1024> events_;

  // Servo-thread state.
  LinkState link_ = LinkState::kConnecting;
  std::uint64_t tick_ = 0, last_reconnect_tick_ = 0;
  std::uint16_t tx_sequence_ = 0, rx_sequence_ = 0;
  bool have_rx_sequence_ = false, watchdog_tripped_ = false;
  int consecutive_missed_ = 0;
  std::int64_t sample_period_ns_ = 0;  // the board's (DEVICE_INFO); 0: unknown, no phase lock
  std::int64_t phase_shift_ns_ = 0;    // deadline shift the phase lock asks of run() [ns]
  std::atomic<int> phase_slewing_periods_{0};  // consecutive periods at the slew limit; < 0: gave up (single writer)
  std::atomic<double> sample_age_us_{0.0};
  std::uint32_t clamped_channels_ = 0;
  bool rendered_ = false;  // the renderer ran this period
  wire::BoardError last_board_error_ = wire::BoardError::kNone;
  wire::DecoderStats decoder_;
  wire::Frame rx_frame_, tx_frame_;
  wire::State last_state_;
  EffortRequest request_;
  std::array<double, wire::kMaxChannels> command_{};
  std::array<std::uint8_t, wire::kMaxFrameSize> tx_bytes_{}, rx_bytes_{};

  struct AtomicCounters {
    std::atomic<std::uint64_t> ticks{0}, states{0}, states_missing{0}, frames_lost{0}, duplicates{0},
        frames_rejected{0}, host_watchdog_trips{0}, loop_stalls{0}, clamped_ticks{0},
        non_finite_commands{0}, disconnects{0}, reconnects{0}, board_resets{0}, send_failures{0},
        events_dropped{0};
    std::array<std::atomic<std::uint64_t>, wire::kRejectReasons> rejected{};
  } counters_;
};

}  // namespace uhaptics
