#include "uhaptics/backends/servo_loop.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <time.h>

#include <Eigen/Core>
#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <sstream>

#include "uhaptics/backends/device_definition.hpp"
#include "uhaptics/core/fault.hpp"
#include "uhaptics/core/limits.hpp"
#include "uhaptics/core/sanitized_build.hpp"

namespace uhaptics {

namespace {

// "'TAU' (code 2)": a protocol device code with the registered device that has it.
std::string deviceLabel(wire::DeviceType code) {
  const auto raw = std::to_string(static_cast<int>(code));
  if (code == wire::DeviceType::kTestPlant) return "'test plant' (code 0)";
  const DeviceDefinition* d = findDevice(code);
  return d ? "'" + d->title + "' (code " + raw + ")" : "code " + raw + " (no registered device)";
}


std::int64_t monotonicNs() noexcept {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1000000000LL + ts.tv_nsec;
}

timespec toTimespec(std::int64_t ns) noexcept {
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(ns / 1000000000LL);
  ts.tv_nsec = static_cast<long>(ns % 1000000000LL);
  return ts;
}

std::string hex(unsigned v, int width) {
  char text[16];
  std::snprintf(text, sizeof text, "%0*x", width, v);
  return text;
}

}  // namespace

void ServoConfig::validate() const {
  if (!(rate_hz >= 500.0 && rate_hz <= 10000.0))
    throw Error("servo rate " + std::to_string(rate_hz) + " Hz outside the supported 500 .. 10000 Hz");
  if (watchdog_periods < 1 || watchdog_periods > 1000)
    throw Error("watchdog_periods " + std::to_string(watchdog_periods) + " outside 1 .. 1000");
  if (board_watchdog_us != 0 && (board_watchdog_us < 1000 || board_watchdog_us > 1000000))
    throw Error("board_watchdog_us " + std::to_string(board_watchdog_us) + " outside 1000 .. 1000000 (0 = default)");
  if (receive_timeout_us < 0 || realtime_priority < 1 || realtime_priority > 99 ||
      reconnect_interval_ms < 1 || handshake_timeout_ms < 1)
    throw Error("servo config: receive_timeout_us >= 0, realtime_priority 1..99, "
                "reconnect_interval_ms >= 1 and handshake_timeout_ms >= 1 required");
}

SafetyOutcome enforceEffortLimits(double* efforts, int n, const double* limits) noexcept {
  SafetyOutcome out;
  Eigen::Map<Eigen::VectorXd> cmd(efforts, n);
  const Eigen::Map<const Eigen::VectorXd> lim(limits, n);
  if (zeroIfNonFinite(cmd) != Fault::kNone) {
    out.non_finite = true;
    return out;
  }
  for (int i = 0; i < n; ++i)
    if (std::abs(efforts[i]) > limits[i]) out.exceeded_mask |= 1u << i;
  out.scale = scaleIntoBox(cmd, lim);
  clampSymmetric(cmd, lim);  // rounding of the scaled values can leave them one ulp outside
  return out;
}

const char* toString(ServoEventKind k) noexcept {
  switch (k) {
    case ServoEventKind::kFrameRejected: return "frame rejected";
    case ServoEventKind::kStateMissing: return "no valid STATE this period";
    case ServoEventKind::kFramesLost: return "frames lost";
    case ServoEventKind::kDuplicateFrame: return "duplicate frame discarded";
    case ServoEventKind::kBoardError: return "board error";
    case ServoEventKind::kHostWatchdog: return "host watchdog: zero commanded";
    case ServoEventKind::kLoopStalled: return "servo loop stalled: zero commanded";
    case ServoEventKind::kResumed: return "resumed";
    case ServoEventKind::kClamped: return "command clamped to device limit";
    case ServoEventKind::kNonFiniteCommand: return "non-finite command zeroed";
    case ServoEventKind::kDisconnected: return "device disconnected: zero commanded";
    case ServoEventKind::kReconnected: return "device reconnected";
    case ServoEventKind::kBoardReset: return "board reset detected: zero, handshake again";
    case ServoEventKind::kSendFailed: return "send failed";
  }
  return "unknown event";
}

std::string describe(const ServoEvent& e) {
  std::ostringstream s;
  s << "tick " << e.tick << ": " << toString(e.kind);
  switch (e.kind) {
    case ServoEventKind::kFrameRejected: s << " (" << wire::toString(static_cast<wire::Reject>(e.detail)) << ")"; break;
    case ServoEventKind::kBoardError: s << " (" << wire::toString(static_cast<wire::BoardError>(e.detail)) << ")"; break;
    case ServoEventKind::kClamped: s << " (actuator " << int(e.detail) << " requested " << e.value << ")"; break;
    case ServoEventKind::kNonFiniteCommand: s << " (actuator " << int(e.detail) << ")"; break;
    case ServoEventKind::kFramesLost:
    case ServoEventKind::kHostWatchdog:
    case ServoEventKind::kLoopStalled: s << " (" << e.value << ")"; break;
    case ServoEventKind::kSendFailed: s << " (" << toString(static_cast<TransportStatus>(e.detail)) << ")"; break;
    default: break;
  }
  return s.str();
}

ServoLoop::ServoLoop(const DeviceDescriptor& device, Transport& transport, const ServoConfig& config,
                     ServoRenderer* renderer)
    : device_(device),
      transport_(transport),
      config_(config),
      renderer_(renderer),
      period_ns_(static_cast<std::int64_t>(std::llround(1e9 / config.rate_hz))),
      receive_timeout_us_(config.receive_timeout_us > 0 ? config.receive_timeout_us
                                                        : static_cast<int>(5e5 / config.rate_hz)),
      board_watchdog_us_(config.board_watchdog_us > 0
                             ? config.board_watchdog_us
                             : std::max<std::uint32_t>(5000, static_cast<std::uint32_t>(5e6 / config.rate_hz))),
      timing_(1e6 / config.rate_hz) {
  device_.validate();
  config_.validate();
  request_.count = device_.actuators;
}

ServoLoop::~ServoLoop() { stop(); }

void ServoLoop::emit(ServoEventKind kind, std::uint8_t detail, double value) noexcept {
  if (!events_.push(ServoEvent{tick_, kind, detail, value})) bump(counters_.events_dropped);
}

bool ServoLoop::sendFrame(wire::Frame& frame) noexcept {
  frame.device = device_.type;
  frame.version = device_.protocol_version;
  frame.sequence = tx_sequence_++;
  const std::size_t size = wire::encode(frame, tx_bytes_.data(), tx_bytes_.size());
  if (size == 0) return false;  // unreachable for frames built here (finite, counts checked)
  const TransportStatus s = transport_.send(tx_bytes_.data(), size, receive_timeout_us_);
  if (s == TransportStatus::kDisconnected) {
    onDisconnected();
    return false;
  }
  if (s != TransportStatus::kOk) {
    bump(counters_.send_failures);
    emit(ServoEventKind::kSendFailed, static_cast<std::uint8_t>(s));
    return false;
  }
  return true;
}

void ServoLoop::sendZero() noexcept {
  tx_frame_ = wire::makeCommand(device_.type, 0, wire::CommandMode::kZero, command_.data(), device_.actuators);
  sendFrame(tx_frame_);
}

// Waits for a frame of one type, discarding others; malformed frames are counted.
bool ServoLoop::awaitFrame(wire::MessageType type, int timeout_us, wire::Frame& out,
                           TransportStatus& status) noexcept {
  const std::int64_t deadline = monotonicNs() + static_cast<std::int64_t>(timeout_us) * 1000;
  for (;;) {
    const std::int64_t left_us = (deadline - monotonicNs()) / 1000;
    if (left_us <= 0) { status = TransportStatus::kTimeout; return false; }
    std::size_t got = 0;
    status = transport_.receive(rx_bytes_.data(), rx_bytes_.size(), got, static_cast<int>(left_us));
    if (status == TransportStatus::kDisconnected || status == TransportStatus::kTimeout) return false;
    if (status != TransportStatus::kOk) continue;
    const wire::Reject r = wire::decode(rx_bytes_.data(), got, out, &decoder_);
    if (r == wire::Reject::kNone && out.type == type) return true;
  }
}

ServoLoop::HandshakeResult ServoLoop::handshake(int timeout_us, wire::DeviceInfo& info) noexcept {
  // Discard whatever the board queued before (answers to an older session).
  std::size_t got = 0;
  while (transport_.receive(rx_bytes_.data(), rx_bytes_.size(), got, 0) == TransportStatus::kOk) {}

  const std::uint32_t nonce = static_cast<std::uint32_t>(monotonicNs()) | 1u;
  tx_frame_ = wire::makeHello(device_.type, 0, nonce);
  tx_frame_.hello.min_version = wire::kMinProtocolVersion;
  tx_frame_.hello.max_version = wire::kMaxProtocolVersion;
  // HELLO travels in the frozen version-1 header; the selected version applies after it.
  if (!sendFrame(tx_frame_)) return link_ == LinkState::kDisconnected ? HandshakeResult::kDisconnected : HandshakeResult::kNoAnswer;
  TransportStatus status = TransportStatus::kOk;
  do {
    if (!awaitFrame(wire::MessageType::kDeviceInfo, timeout_us, rx_frame_, status))
      return status == TransportStatus::kDisconnected ? HandshakeResult::kDisconnected : HandshakeResult::kNoAnswer;
  } while (rx_frame_.info.nonce != nonce);
  info = rx_frame_.info;
  sample_period_ns_ = info.sample_rate_hz > 0 ? static_cast<std::int64_t>(std::llround(1e9 / info.sample_rate_hz)) : 0;
  phase_slewing_periods_.store(0, std::memory_order_relaxed);
  if (info.selected_version == 0 || info.selected_version != device_.protocol_version)
    return HandshakeResult::kVersionMismatch;
  if (rx_frame_.device != device_.type || info.joint_count != device_.joints ||
      info.actuator_count != device_.actuators)
    return HandshakeResult::kWrongDevice;

  tx_frame_ = wire::Frame{};
  tx_frame_.type = wire::MessageType::kConfigure;
  tx_frame_.configure.watchdog_timeout_us = board_watchdog_us_;
  const std::uint16_t configure_sequence = tx_sequence_;
  if (!sendFrame(tx_frame_)) return link_ == LinkState::kDisconnected ? HandshakeResult::kDisconnected : HandshakeResult::kNoAnswer;
  do {
    if (!awaitFrame(wire::MessageType::kAck, timeout_us, rx_frame_, status))
      return status == TransportStatus::kDisconnected ? HandshakeResult::kDisconnected : HandshakeResult::kNoAnswer;
  } while (rx_frame_.ack.acked_sequence != configure_sequence);
  if (rx_frame_.ack.error != wire::BoardError::kNone) return HandshakeResult::kRefused;

  have_rx_sequence_ = false;
  consecutive_missed_ = 0;
  link_ = LinkState::kRunning;
  command_.fill(0.0);
  sendZero();  // primes the request/answer cycle: its STATE is what the first tick reads
  return HandshakeResult::kOk;
}

wire::DeviceInfo ServoLoop::connect() {
  if (running()) throw Error("ServoLoop::connect() while the servo thread runs");
  wire::DeviceInfo info;
  const std::string who = "device '" + device_.name + "' on " + transport_.describe() + ": ";
  const auto versions = [](unsigned lo, unsigned hi) { return std::to_string(lo) + ".." + std::to_string(hi); };
  link_ = LinkState::kConnecting;
  switch (handshake(config_.handshake_timeout_ms * 1000, info)) {
    case HandshakeResult::kOk: return info;
    case HandshakeResult::kNoAnswer:
      throw Error(who + "no answer to HELLO within " + std::to_string(config_.handshake_timeout_ms) +
                  " ms. Is the board's firmware running and speaking the uhaptics protocol "
                  "(devices/protocol/PROTOCOL.md)?");
    case HandshakeResult::kDisconnected:
      throw Error(who + "the device disconnected during the handshake");
    case HandshakeResult::kVersionMismatch:
      throw Error(who + "protocol version mismatch: this host speaks " +
                  versions(wire::kMinProtocolVersion, wire::kMaxProtocolVersion) + " and is set to use " +
                  std::to_string(device_.protocol_version) + " (usb/protocol_version in the parameter file); the board (firmware 0x" +
                  hex(info.firmware_version, 8) + ") speaks " + versions(info.min_version, info.max_version) +
                  ". Update the board's firmware or uhaptics so that they share a version.");
    case HandshakeResult::kWrongDevice:
      throw Error(who + "the board reports device " + deviceLabel(rx_frame_.device) + " with " +
                  std::to_string(info.joint_count) + " joints and " + std::to_string(info.actuator_count) +
                  " actuators; expected " + deviceLabel(device_.type) + " with " + std::to_string(device_.joints) +
                  " and " + std::to_string(device_.actuators) + ". Check the vendor/product id in the parameter file.");
    case HandshakeResult::kRefused:
      throw Error(who + "the board refused CONFIGURE (" + wire::toString(rx_frame_.ack.error) +
                  ", watchdog " + std::to_string(board_watchdog_us_) + " us)");
  }
  throw Error(who + "handshake failed");
}

std::string ServoLoop::start() {
  if (running()) return realtimeNote();
  if (link_ != LinkState::kRunning) throw Error("ServoLoop::start(): call connect() first");
  running_.store(true, std::memory_order_release);
  thread_ = std::thread([this] { run(); });
  // Wait (bounded) for the thread to report its scheduling so the note is accurate.
  for (int i = 0; i < 100 && realtime_state_.load() == 0 && config_.realtime; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  return realtimeNote();
}

void ServoLoop::stop() {
  if (!running_.exchange(false, std::memory_order_acq_rel)) return;
  if (thread_.joinable()) thread_.join();
}

std::string ServoLoop::realtimeNote() const {
  const int s = realtime_state_.load();
  if (!config_.realtime) return "real-time scheduling not requested (SCHED_OTHER)";
  if (s == 0) return "real-time scheduling pending";
  const int m = memory_state_.load();
  const std::string memory = !config_.lock_memory ? "memory not locked (not requested)"
                             : kSanitizedBuild    ? "memory not locked (a sanitizer's shadow memory cannot be)"
                             : m == 1             ? "memory locked"
                             : m == 0             ? "memory lock pending"
                                                  : std::string("memory lock refused (") + std::strerror(m) +
                                                        "; raise memlock in /etc/security/limits.conf)";
  if (s == 1) return "servo thread runs SCHED_FIFO priority " + std::to_string(config_.realtime_priority) + "; " + memory;
  return std::string("SCHED_FIFO refused (") + std::strerror(s) +
         "): running SCHED_OTHER, expect more jitter. Grant it with `ulimit -r " +
         std::to_string(config_.realtime_priority) + "` (rtprio in /etc/security/limits.conf) or CAP_SYS_NICE; " + memory;
}

void ServoLoop::run() noexcept {
  if (config_.realtime) {
    sched_param param{};
    param.sched_priority = config_.realtime_priority;
    const int err = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param);
    realtime_state_.store(err == 0 ? 1 : err);
    if (config_.lock_memory && !kSanitizedBuild) {
      // Touch the stack the loop will use before locking, so it is resident too.
      volatile char stack[64 * 1024];
      for (std::size_t i = 0; i < sizeof(stack); i += 4096) stack[i] = 0;
      memory_state_.store(mlockall(MCL_CURRENT) == 0 ? 1 : errno);
    }
  }
  std::int64_t deadline = monotonicNs();
  std::int64_t previous_wake = deadline;
  bool first = true;
  while (running_.load(std::memory_order_acquire)) {
    deadline += period_ns_;
    const timespec ts = toTimespec(deadline);
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {}
    const std::int64_t wake = monotonicNs();
    const std::int64_t latency = wake - deadline;
    const std::uint64_t missed = latency >= period_ns_ ? static_cast<std::uint64_t>(latency / period_ns_) : 0;
    if (!first) timing_.record(wake - previous_wake, latency, missed);
    first = false;
    previous_wake = wake;
    if (missed > 0) {
      // Skip the deadlines already past instead of bursting through them.
      deadline += static_cast<std::int64_t>(missed) * period_ns_;
      if (missed >= static_cast<std::uint64_t>(config_.watchdog_periods) && link_ == LinkState::kRunning) {
        bump(counters_.loop_stalls);
        emit(ServoEventKind::kLoopStalled, 0, static_cast<double>(missed));
        // The STATE waiting now answers a command sent long ago: do not act on it this period.
        tripWatchdog(ServoEventKind::kHostWatchdog, static_cast<double>(missed));
      }
    }
    tick();
    deadline += phase_shift_ns_;
    phase_shift_ns_ = 0;
  }
  if (link_ == LinkState::kRunning) sendZero();  // leave the device unpowered on close
  // Readers must not take the last reading for a live one once nothing runs.
  DeviceSnapshot last;
  fillSnapshot(last);
  last.link = LinkState::kStopped;
  if (renderer_ != nullptr) renderer_->noReading(last);  // it renders no more
  snapshots_.write(last);  // command_sent stays zero: zero was the last command
}

void ServoLoop::onDisconnected() noexcept {
  if (link_ == LinkState::kDisconnected) return;
  link_ = LinkState::kDisconnected;
  last_reconnect_tick_ = tick_;
  command_.fill(0.0);  // nothing can be sent; the board's watchdog (or lost power) zeroes it
  bump(counters_.disconnects);
  emit(ServoEventKind::kDisconnected);
}

void ServoLoop::tripWatchdog(ServoEventKind why, double periods) noexcept {
  command_.fill(0.0);
  if (watchdog_tripped_) return;
  watchdog_tripped_ = true;
  bump(counters_.host_watchdog_trips);
  emit(why, 0, periods);
}

void ServoLoop::tick() noexcept {
  ++tick_;
  rendered_ = false;
  bump(counters_.ticks);
  switch (link_) {
    case LinkState::kDisconnected: {
      const std::uint64_t interval = static_cast<std::uint64_t>(
          std::max(1.0, config_.reconnect_interval_ms * 1e-3 * config_.rate_hz));
      if (tick_ - last_reconnect_tick_ >= interval) {
        last_reconnect_tick_ = tick_;
        // The only step that may allocate (libusb enumeration); taken only while the device is away.
        if (transport_.reconnect()) {
          bump(counters_.reconnects);
          emit(ServoEventKind::kReconnected);
          link_ = LinkState::kConnecting;
        }
      }
      break;
    }
    case LinkState::kConnecting: {
      wire::DeviceInfo info;
      if (handshake(receive_timeout_us_, info) == HandshakeResult::kOk) {
        watchdog_tripped_ = false;
        emit(ServoEventKind::kResumed);
      }
      break;
    }
    case LinkState::kRunning: runningTick(); break;
    case LinkState::kStopped: break;  // only in the snapshot run() leaves behind
  }
  if (renderer_ != nullptr && !rendered_) {
    DeviceSnapshot state;
    fillSnapshot(state);
    renderer_->noReading(state);
  }
  publish();
}

void ServoLoop::runningTick() noexcept {
  // 1. Receive: the answer to the last COMMAND, then anything else queued; keep the newest STATE.
  bool fresh = false;
  int timeout = receive_timeout_us_;
  for (int drained = 0; drained < 8; ++drained, timeout = 0) {
    std::size_t got = 0;
    const TransportStatus s = transport_.receive(rx_bytes_.data(), rx_bytes_.size(), got, timeout);
    if (s == TransportStatus::kDisconnected) { onDisconnected(); return; }
    if (s != TransportStatus::kOk) break;
    const wire::Reject r = wire::decode(rx_bytes_.data(), got, rx_frame_, &decoder_);
    if (r != wire::Reject::kNone) {
      bump(counters_.frames_rejected);
      bump(counters_.rejected[static_cast<std::size_t>(r)]);
      emit(ServoEventKind::kFrameRejected, static_cast<std::uint8_t>(r));
      continue;
    }
    if (rx_frame_.type != wire::MessageType::kState || rx_frame_.device != device_.type ||
        rx_frame_.state.count != device_.joints)
      continue;  // a late handshake answer or a frame for another device: not a state
    const std::uint16_t seq = rx_frame_.sequence;
    const bool reset = (rx_frame_.state.status & wire::status::kJustReset) != 0 ||
                       (rx_frame_.state.status & wire::status::kConfigured) == 0;
    if (reset) {
      // The board rebooted (or lost its session): zero, then a fresh handshake next period.
      bump(counters_.board_resets);
      emit(ServoEventKind::kBoardReset);
      command_.fill(0.0);
      sendZero();
      link_ = LinkState::kConnecting;
      return;
    }
    if (have_rx_sequence_ && !wire::sequenceAfter(seq, rx_sequence_)) {
      bump(counters_.duplicates);
      emit(ServoEventKind::kDuplicateFrame);
      continue;
    }
    if (have_rx_sequence_) {
      const std::uint16_t gap = static_cast<std::uint16_t>(seq - rx_sequence_ - 1);
      if (gap > 0) {
        bump(counters_.frames_lost, gap);
        emit(ServoEventKind::kFramesLost, 0, gap);
      }
    }
    have_rx_sequence_ = true;
    rx_sequence_ = seq;
    last_state_ = rx_frame_.state;
    fresh = true;
  }

  // 2. Host watchdog, board status and the phase lock.
  if (fresh) {
    bump(counters_.states);
    lockPhase();
    consecutive_missed_ = 0;
    if (last_state_.error != last_board_error_) {
      if (last_state_.error != wire::BoardError::kNone)
        emit(ServoEventKind::kBoardError, static_cast<std::uint8_t>(last_state_.error));
      last_board_error_ = last_state_.error;
    }
    if (watchdog_tripped_) {
      watchdog_tripped_ = false;
      emit(ServoEventKind::kResumed);
    }
  } else {
    bump(counters_.states_missing);
    if (consecutive_missed_++ == 0) emit(ServoEventKind::kStateMissing);
    if (consecutive_missed_ >= config_.watchdog_periods)
      tripWatchdog(ServoEventKind::kHostWatchdog, consecutive_missed_);
  }

  // 3. Command: renderer or graphics request, then the safety stage; zero while tripped.
  computeCommand(fresh);

  // 4. Send (the board answers with the next STATE).
  tx_frame_ = wire::makeCommand(device_.type, 0,
                                watchdog_tripped_ ? wire::CommandMode::kZero : wire::CommandMode::kEffort,
                                command_.data(), device_.actuators);
  sendFrame(tx_frame_);
}

void ServoLoop::lockPhase() noexcept {
  // The sample's age when the previous COMMAND arrived; unsigned difference: the clock wraps.
  const std::int64_t age_ns =
      static_cast<std::int64_t>(static_cast<std::uint32_t>(last_state_.board_time_us - last_state_.sample_time_us[0])) * 1000;
  // Reported as a mean over about 50 periods (single writer), so jitter does not hide the phase.
  const double previous = sample_age_us_.load(std::memory_order_relaxed);
  const double age_us = static_cast<double>(age_ns) * 1e-3;
  sample_age_us_.store(previous == 0.0 ? age_us : previous + 0.02 * (age_us - previous), std::memory_order_relaxed);
  if (!config_.phase_lock || sample_period_ns_ <= 0 || age_ns >= sample_period_ns_) return;
  int slewing = phase_slewing_periods_.load(std::memory_order_relaxed);
  if (slewing < 0) return;
  // A proportional step of 1/8 of the error, slewed to 2 % of a period so that locking never looks
  // like a missed deadline; an older sample means the command comes late in the board's period.
  const std::int64_t error = age_ns - sample_period_ns_ / 2;
  const std::int64_t slew = period_ns_ / 50;
  const std::int64_t step = std::clamp<std::int64_t>(error / 8, -slew, slew);
  slewing = (step == slew || step == -slew) ? slewing + 1 : 0;
  // Past the limit the age does not follow the shifts: every further one would only stretch the period.
  phase_slewing_periods_.store(slewing > kPhaseLockGiveUpPeriods ? -1 : slewing, std::memory_order_relaxed);
  if (slewing > kPhaseLockGiveUpPeriods) return;
  phase_shift_ns_ -= step;
}

void ServoLoop::computeCommand(bool fresh) noexcept {
  if (watchdog_tripped_) {
    command_.fill(0.0);
    return;
  }
  if (!fresh) return;  // a single late STATE: hold the previous command (within the watchdog)
  requests_.read(request_);
  std::array<double, wire::kMaxChannels> raw{};
  DeviceSnapshot state;
  fillSnapshot(state);
  if (renderer_ != nullptr) {
    rendered_ = true;
    renderer_->render(state, request_, raw.data());
  } else {
    for (int i = 0; i < device_.actuators; ++i) raw[i] = i < request_.count ? request_.effort[i] : 0.0;
  }
  const std::array<double, wire::kMaxChannels> requested = raw;
  const SafetyOutcome safety = enforceEffortLimits(raw.data(), device_.actuators, device_.effort_limit.data());
  if (safety.non_finite) {
    bump(counters_.non_finite_commands);
    int channel = 0;
    while (channel < device_.actuators && std::isfinite(requested[channel])) ++channel;
    emit(ServoEventKind::kNonFiniteCommand, static_cast<std::uint8_t>(channel));
  }
  if (safety.exceeded_mask != 0) bump(counters_.clamped_ticks);
  // Log a channel when it starts exceeding its limit, not every period it stays there.
  const std::uint32_t started = safety.exceeded_mask & ~clamped_channels_;
  for (int i = 0; i < device_.actuators; ++i)
    if (started & (1u << i)) emit(ServoEventKind::kClamped, static_cast<std::uint8_t>(i), requested[i]);
  clamped_channels_ = safety.exceeded_mask;
  command_ = raw;
}

void ServoLoop::fillSnapshot(DeviceSnapshot& s) const noexcept {
  s.tick = tick_;
  s.link = link_;
  s.host_watchdog_tripped = watchdog_tripped_;
  s.board_status = last_state_.status;
  s.board_error = last_state_.error;
  s.board_time_us = last_state_.board_time_us;
  s.joints = device_.joints;
  s.actuators = device_.actuators;
  for (int i = 0; i < device_.joints; ++i) {
    s.position[i] = static_cast<double>(last_state_.position[i]);
    s.sample_time_us[i] = last_state_.sample_time_us[i];
  }
}

void ServoLoop::publish() noexcept {
  DeviceSnapshot s;
  fillSnapshot(s);
  for (int i = 0; i < device_.actuators; ++i) s.command_sent[i] = watchdog_tripped_ ? 0.0 : command_[i];
  snapshots_.write(s);
}

ServoCounters ServoLoop::counters() const noexcept {
  ServoCounters c;
  const auto& a = counters_;
  const auto get = [](const std::atomic<std::uint64_t>& v) { return v.load(std::memory_order_relaxed); };
  c.ticks = get(a.ticks);
  c.states = get(a.states);
  c.states_missing = get(a.states_missing);
  c.frames_lost = get(a.frames_lost);
  c.duplicates = get(a.duplicates);
  c.frames_rejected = get(a.frames_rejected);
  c.host_watchdog_trips = get(a.host_watchdog_trips);
  c.loop_stalls = get(a.loop_stalls);
  c.clamped_ticks = get(a.clamped_ticks);
  c.non_finite_commands = get(a.non_finite_commands);
  c.disconnects = get(a.disconnects);
  c.reconnects = get(a.reconnects);
  c.board_resets = get(a.board_resets);
  c.send_failures = get(a.send_failures);
  c.events_dropped = get(a.events_dropped);
  for (std::size_t i = 0; i < c.rejected_by_reason.size(); ++i) c.rejected_by_reason[i] = get(a.rejected[i]);
  return c;
}

std::string ServoLoop::summary() const {
  const ServoCounters c = counters();
  std::ostringstream s;
  s << "servo loop '" << device_.name << "' at " << config_.rate_hz << " Hz on " << transport_.describe() << "\n"
    << "  " << realtimeNote() << "\n"
    << "  ticks " << c.ticks << ", states " << c.states << ", missing " << c.states_missing << ", lost "
    << c.frames_lost << ", duplicates " << c.duplicates << ", rejected " << c.frames_rejected
    << ", host watchdog trips " << c.host_watchdog_trips << ", loop stalls " << c.loop_stalls
    << ", clamped ticks " << c.clamped_ticks << ", non-finite commands " << c.non_finite_commands
    << ", disconnects " << c.disconnects << ", reconnects " << c.reconnects << ", board resets "
    << c.board_resets << ", events dropped " << c.events_dropped << "\n";
  for (std::size_t i = 1; i < c.rejected_by_reason.size(); ++i)
    if (c.rejected_by_reason[i] > 0)
      s << "  rejected (" << wire::toString(static_cast<wire::Reject>(i)) << "): " << c.rejected_by_reason[i] << "\n";
  s << "  board sample age at COMMAND " << sampleAgeUs() << " us (phase lock "
    << (!config_.phase_lock ? "off" : phase_slewing_periods_.load(std::memory_order_relaxed) < 0 ? "given up: the board's age does not follow the host's phase" : "on")
    << ")\n";
  s << "  " << timing().format();
  return s.str();
}

}  // namespace uhaptics
