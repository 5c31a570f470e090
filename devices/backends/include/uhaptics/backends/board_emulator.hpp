#pragma once
// An in-process controller board: the firmware side of devices/protocol/PROTOCOL.md running on a
// BoardPlant, exposed to the host as a Transport. The host path (protocol, handshake, timing,
// watchdogs, error reports) is exercised end to end exactly as with hardware, and faults that are
// hard to produce on a bench are injected on demand.
//
// Board behaviour (what real firmware must do too):
// - HELLO -> DEVICE_INFO with the highest common version (0 and error report when none).
// - CONFIGURE -> ACK; sets the board watchdog. Before CONFIGURE, COMMANDs are refused (outputs 0).
// - COMMAND -> applied after clamping to the board's own limits, answered by one STATE.
// - Board watchdog: no valid COMMAND for the configured timeout -> outputs zero, STATE flags it.
// - Sensors are sampled at the board rate; each reading carries its sample's board timestamp.
//
// Thread safety: Transport calls (servo thread) and fault injection/inspection (test thread) may run
// concurrently; an internal mutex stands in for the USB cable. (The emulator is a test fixture:
// its lock is not on the host's code path, which stays lock-free.)
#include <array>
#include <chrono>
#include <cstdint>
#include <mutex>

#include "uhaptics/backends/board_plant.hpp"
#include "uhaptics/protocol/transport.hpp"
#include "uhaptics/protocol/wire_protocol.hpp"

namespace uhaptics {

class BoardEmulator final : public Transport {
 public:
  struct Config {
    wire::DeviceType device = wire::DeviceType::kTestPlant;
    double sample_rate_hz = 1000.0;
    std::array<double, wire::kMaxChannels> effort_limit{};  // board-side clamp (0 = no limit)
    std::uint8_t min_version = wire::kMinProtocolVersion;
    std::uint8_t max_version = wire::kMaxProtocolVersion;
    std::uint32_t firmware_version = 0x00010000;
  };
  /// Fault kinds the emulator can inject into board -> host traffic (and the link itself).
  enum class Fault : std::uint8_t { kDrop, kCorrupt, kDuplicate, kDelay };

  BoardEmulator(const Config& config, BoardPlant& plant);

  // Transport (host side).
  TransportStatus send(const std::uint8_t* data, std::size_t size, int timeout_us) noexcept override;
  TransportStatus receive(std::uint8_t* buffer, std::size_t capacity, std::size_t& received,
                          int timeout_us) noexcept override;
  bool reconnect() noexcept override;
  const char* describe() const noexcept override { return "in-process board emulator"; }

  // Fault injection (any thread).
  /// Applies fault to the next `frames` frames the board sends. kDelay holds each of them until the
  /// board has received `delay_periods` more host frames (one per servo period), and with it every
  /// frame queued behind (one bulk pipe keeps its order): a delay counted in periods, so tests do
  /// not depend on the test machine's scheduling.
  void inject(Fault fault, int frames, int delay_periods = 0) noexcept;
  /// Board reboots: configuration, watchdog and sequence numbers are lost, outputs go to zero.
  void resetBoard() noexcept;
  /// Cable pulled: every transfer fails with kDisconnected and the board (unpowered) stops driving.
  void unplug() noexcept;
  /// Cable back: reconnect() succeeds; the board boots fresh (as after resetBoard()).
  void replug() noexcept;
  /// Advances the board to now without host traffic (a dead host: lets the board watchdog act).
  void service() noexcept;
  /// The user's hand on the board's device: BoardPlant::setUserForce() of its plant (a CHAI3D
  /// session's scripted hand moves the emulated device as it moves the simulated one).
  void setUserForce(const Vec3& force) noexcept;
  /// BoardPlant::setSceneForce() of its plant: what the host's scene asks for, for a referee.
  void setSceneForce(const Vec3& force) noexcept;
  /// BoardPlant::readUserPoint() of its plant: where that hand holds the device.
  bool readUserPoint(Vec3& position, Vec3& velocity) noexcept;

  // Inspection (any thread).
  struct Snapshot {
    bool configured = false;
    bool outputs_enabled = false;
    std::uint64_t commands_applied = 0;
    std::uint64_t watchdog_trips = 0;
    std::uint64_t frames_rejected = 0;   // host frames the board's decoder refused
    std::array<double, wire::kMaxChannels> applied{};  // efforts currently on the actuators
  };
  Snapshot snapshot() const noexcept;

 private:
  using Clock = std::chrono::steady_clock;
  struct Outgoing {
    std::array<std::uint8_t, wire::kMaxFrameSize> bytes{};
    std::size_t size = 0;
    std::uint64_t release_after = 0;  // deliverable once rx_frames_ reaches this
  };
  static constexpr std::size_t kQueue = 32;

  void advanceLocked(Clock::time_point now) noexcept;
  void bootLocked(Clock::time_point now) noexcept;
  void zeroOutputsLocked() noexcept;
  void handleLocked(const wire::Frame& in, Clock::time_point now) noexcept;
  void emitLocked(wire::Frame& out, Clock::time_point now) noexcept;
  void pushLocked(const std::uint8_t* bytes, std::size_t size, std::uint64_t release_after) noexcept;
  std::uint32_t boardMicros(Clock::time_point t) const noexcept;

  const Config config_;
  BoardPlant& plant_;
  mutable std::mutex mutex_;
  // Board state.
  Clock::time_point boot_time_{}, plant_time_{}, last_command_time_{};
  bool configured_ = false, outputs_enabled_ = false, just_reset_ = true,  // just_reset_: boot until HELLO
       watchdog_tripped_ = false;
  bool plugged_ = true;
  bool started_ = false;  // the outputs were enabled once: the plant integrates from then on
  std::uint8_t version_ = wire::kProtocolVersion;
  std::uint32_t watchdog_us_ = 0;
  std::uint16_t tx_sequence_ = 0, last_command_sequence_ = 0;
  wire::BoardError pending_error_ = wire::BoardError::kNone;
  std::array<double, wire::kMaxChannels> applied_{}, samples_{};
  std::array<std::uint32_t, wire::kMaxChannels> sample_time_us_{};
  wire::DecoderStats rx_stats_;
  std::uint64_t commands_applied_ = 0, watchdog_trips_ = 0;
  // Link state.
  std::array<Outgoing, kQueue> queue_{};
  std::size_t queue_head_ = 0, queue_size_ = 0;
  Fault fault_ = Fault::kDrop;
  int fault_frames_ = 0;
  int fault_delay_periods_ = 0;
  std::uint64_t rx_frames_ = 0;  // host frames received
};

/// A handle on the board emulator behind an "emulated" joint I/O (JointIoOptions::emulator_control),
/// for whoever drives the device from outside: a test or the soak run injects faults mid-session
/// while the application keeps using the device. The joint I/O attaches its emulator in open() and
/// detaches it in close(); while detached every call does nothing and reports false. Thread-safe.
class BoardEmulatorControl {
 public:
  /// Whether an emulator is attached (the joint I/O is open).
  bool attached() const noexcept;
  /// BoardEmulator::inject(): the next `frames` frames the board sends (one per servo period) are
  /// dropped (the board is silent that long), corrupted, duplicated or delayed.
  bool inject(BoardEmulator::Fault fault, int frames, int delay_periods = 0) noexcept;
  bool unplug() noexcept;
  bool replug() noexcept;
  bool resetBoard() noexcept;
  bool snapshot(BoardEmulator::Snapshot& out) const noexcept;

  /// The joint I/O's side: attach(&emulator) after making it, attach(nullptr) before destroying it.
  void attach(BoardEmulator* emulator) noexcept;

 private:
  mutable std::mutex mutex_;
  BoardEmulator* emulator_ = nullptr;
};

}  // namespace uhaptics
