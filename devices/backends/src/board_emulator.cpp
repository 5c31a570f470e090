#include "uhaptics/backends/board_emulator.hpp"

#include <algorithm>
#include <cmath>
#include <thread>

namespace uhaptics {

BoardEmulator::BoardEmulator(const Config& config, BoardPlant& plant) : config_(config), plant_(plant) {
  const std::lock_guard<std::mutex> lock(mutex_);
  bootLocked(Clock::now());
}

std::uint32_t BoardEmulator::boardMicros(Clock::time_point t) const noexcept {
  return static_cast<std::uint32_t>(
      std::chrono::duration_cast<std::chrono::microseconds>(t - boot_time_).count());
}

void BoardEmulator::zeroOutputsLocked() noexcept {
  applied_.fill(0.0);
  plant_.applyCommand(applied_.data());
}

void BoardEmulator::bootLocked(Clock::time_point now) noexcept {
  boot_time_ = plant_time_ = last_command_time_ = now;
  configured_ = outputs_enabled_ = watchdog_tripped_ = false;
  just_reset_ = true;
  watchdog_us_ = 0;
  tx_sequence_ = last_command_sequence_ = 0;
  pending_error_ = wire::BoardError::kNone;
  queue_size_ = 0;
  zeroOutputsLocked();
  plant_.readJoints(samples_.data());
  sample_time_us_.fill(0);
}

// Runs the board's sample loop from plant_time_ to now: integrate, sample, check the watchdog.
void BoardEmulator::advanceLocked(Clock::time_point now) noexcept {
  const auto step = std::chrono::duration_cast<Clock::duration>(
      std::chrono::duration<double>(1.0 / config_.sample_rate_hz));
  const double dt = std::chrono::duration<double>(step).count();
  while (plant_time_ + step <= now) {
    plant_time_ += step;
    if (plugged_) {
      if (outputs_enabled_ && watchdog_us_ > 0 &&
          plant_time_ - last_command_time_ > std::chrono::microseconds(watchdog_us_)) {
        outputs_enabled_ = false;
        watchdog_tripped_ = true;
        ++watchdog_trips_;
        pending_error_ = wire::BoardError::kWatchdogExpired;
        zeroOutputsLocked();
      }
    }
    // Until the host first enables the outputs the device rests as it booted (held by its user
    // while the application starts): a plant left to fall under gravity through the host's start-up
    // would hand the session a device in free fall, not the one its user holds.
    if (started_) plant_.advance(dt);
    plant_.readJoints(samples_.data());
    sample_time_us_.fill(boardMicros(plant_time_));
  }
}

void BoardEmulator::pushLocked(const std::uint8_t* bytes, std::size_t size, std::uint64_t release_after) noexcept {
  if (queue_size_ == kQueue) return;  // a full endpoint FIFO drops, as hardware does
  Outgoing& slot = queue_[(queue_head_ + queue_size_) % kQueue];
  std::copy(bytes, bytes + size, slot.bytes.begin());
  slot.size = size;
  slot.release_after = release_after;
  ++queue_size_;
}

void BoardEmulator::emitLocked(wire::Frame& out, Clock::time_point /*now*/) noexcept {
  out.version = version_;
  out.device = config_.device;
  out.sequence = tx_sequence_++;
  std::array<std::uint8_t, wire::kMaxFrameSize> bytes{};
  const std::size_t size = wire::encode(out, bytes.data(), bytes.size());
  if (size == 0) return;
  std::uint64_t release_after = rx_frames_;
  if (fault_frames_ > 0) {
    --fault_frames_;
    switch (fault_) {
      case Fault::kDrop: return;
      case Fault::kCorrupt: bytes[size / 2] ^= 0x10; break;  // one flipped bit: the CRC must catch it
      case Fault::kDuplicate: pushLocked(bytes.data(), size, release_after); break;
      case Fault::kDelay: release_after += static_cast<std::uint64_t>(fault_delay_periods_); break;
    }
  }
  // FIFO order is kept: a delayed frame holds back the ones behind it (one bulk pipe).
  pushLocked(bytes.data(), size, release_after);
}

void BoardEmulator::handleLocked(const wire::Frame& in, Clock::time_point now) noexcept {
  wire::Frame out;
  switch (in.type) {
    case wire::MessageType::kHello: {
      const std::uint8_t hi = std::min(in.hello.max_version, config_.max_version);
      const std::uint8_t lo = std::max(in.hello.min_version, config_.min_version);
      out.type = wire::MessageType::kDeviceInfo;
      out.info.min_version = config_.min_version;
      out.info.max_version = config_.max_version;
      out.info.selected_version = lo <= hi ? hi : 0;
      out.info.joint_count = static_cast<std::uint8_t>(plant_.jointCount());
      out.info.actuator_count = static_cast<std::uint8_t>(plant_.actuatorCount());
      out.info.sample_rate_hz = static_cast<std::uint16_t>(config_.sample_rate_hz);
      out.info.firmware_version = config_.firmware_version;
      out.info.nonce = in.hello.nonce;
      if (out.info.selected_version != 0) version_ = out.info.selected_version;
      // A new session starts unconfigured with outputs off; the host now knows about the boot.
      configured_ = outputs_enabled_ = false;
      just_reset_ = false;
      zeroOutputsLocked();
      emitLocked(out, now);
      return;
    }
    case wire::MessageType::kConfigure: {
      out.type = wire::MessageType::kAck;
      out.ack.acked_sequence = in.sequence;
      out.ack.acked_type = in.type;
      // Accept 1 ms .. 1 s: shorter cannot be met at USB frame rates, longer is not a watchdog.
      if (in.configure.watchdog_timeout_us < 1000 || in.configure.watchdog_timeout_us > 1000000) {
        out.ack.error = wire::BoardError::kInvalidConfig;
      } else {
        watchdog_us_ = in.configure.watchdog_timeout_us;
        configured_ = true;
        last_command_time_ = now;
      }
      emitLocked(out, now);
      return;
    }
    case wire::MessageType::kCommand: {
      wire::BoardError error = pending_error_;
      pending_error_ = wire::BoardError::kNone;
      if (!configured_ || in.command.count != plant_.actuatorCount()) {
        if (error == wire::BoardError::kNone) error = wire::BoardError::kNotConfigured;
        zeroOutputsLocked();
      } else {
        last_command_time_ = now;
        last_command_sequence_ = in.sequence;
        outputs_enabled_ = in.command.mode == wire::CommandMode::kEffort;
        started_ = started_ || outputs_enabled_;
        bool clamped = false;
        for (int i = 0; i < plant_.actuatorCount(); ++i) {
          double u = outputs_enabled_ ? static_cast<double>(in.command.values[i]) : 0.0;
          const double lim = config_.effort_limit[i];
          if (lim > 0.0 && std::abs(u) > lim) { u = std::copysign(lim, u); clamped = true; }
          applied_[i] = u;
        }
        plant_.applyCommand(applied_.data());
        ++commands_applied_;
        if (clamped && error == wire::BoardError::kNone) error = wire::BoardError::kCommandClamped;
      }
      out.type = wire::MessageType::kState;
      wire::State& s = out.state;
      s.board_time_us = boardMicros(now);
      s.last_command_sequence = last_command_sequence_;
      s.status = static_cast<std::uint8_t>((configured_ ? wire::status::kConfigured : 0) |
                                           (outputs_enabled_ ? wire::status::kOutputsEnabled : 0) |
                                           (watchdog_tripped_ ? wire::status::kWatchdogTripped : 0) |
                                           (just_reset_ ? wire::status::kJustReset : 0));
      s.error = error;
      s.count = static_cast<std::uint8_t>(plant_.jointCount());
      for (int i = 0; i < plant_.jointCount(); ++i) {
        s.position[i] = static_cast<float>(samples_[i]);
        s.sample_time_us[i] = sample_time_us_[i];
      }
      watchdog_tripped_ = false;
      emitLocked(out, now);
      return;
    }
    case wire::MessageType::kDeviceInfo:
    case wire::MessageType::kAck:
    case wire::MessageType::kState:
      pending_error_ = wire::BoardError::kBadFrame;  // board-to-host types have no business here
      return;
  }
}

TransportStatus BoardEmulator::send(const std::uint8_t* data, std::size_t size, int /*timeout_us*/) noexcept {
  const std::lock_guard<std::mutex> lock(mutex_);
  if (!plugged_) return TransportStatus::kDisconnected;
  const auto now = Clock::now();
  advanceLocked(now);
  ++rx_frames_;
  wire::Frame in;
  const wire::Reject r = wire::decode(data, size, in, &rx_stats_);
  if (r != wire::Reject::kNone) {
    pending_error_ = wire::BoardError::kBadFrame;
    return TransportStatus::kOk;  // the bytes did leave the host; the board reports the rejection
  }
  if (in.type == wire::MessageType::kHello) {
    handleLocked(in, now);
  } else if (in.version != version_) {
    pending_error_ = wire::BoardError::kVersionMismatch;
  } else {
    handleLocked(in, now);
  }
  return TransportStatus::kOk;
}

TransportStatus BoardEmulator::receive(std::uint8_t* buffer, std::size_t capacity, std::size_t& received,
                                       int timeout_us) noexcept {
  received = 0;
  const auto deadline = Clock::now() + std::chrono::microseconds(std::max(timeout_us, 0));
  for (;;) {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      if (!plugged_) return TransportStatus::kDisconnected;
      const auto now = Clock::now();
      advanceLocked(now);
      if (queue_size_ > 0) {
        const Outgoing& head = queue_[queue_head_];
        if (head.release_after <= rx_frames_) {
          if (head.size > capacity) return TransportStatus::kError;  // LIBUSB_ERROR_OVERFLOW analogue
          std::copy(head.bytes.begin(), head.bytes.begin() + static_cast<std::ptrdiff_t>(head.size), buffer);
          received = head.size;
          queue_head_ = (queue_head_ + 1) % kQueue;
          --queue_size_;
          return TransportStatus::kOk;
        }
      }
      if (now >= deadline) return TransportStatus::kTimeout;
    }
    // Nothing deliverable: a real pipe would block until the timeout (or an unplug).
    std::this_thread::sleep_until(std::min(deadline, Clock::now() + std::chrono::microseconds(200)));
  }
}

bool BoardEmulator::reconnect() noexcept {
  const std::lock_guard<std::mutex> lock(mutex_);
  return plugged_;
}

void BoardEmulator::inject(Fault fault, int frames, int delay_periods) noexcept {
  const std::lock_guard<std::mutex> lock(mutex_);
  fault_ = fault;
  fault_frames_ = std::max(frames, 0);
  fault_delay_periods_ = std::max(delay_periods, 0);
}

void BoardEmulator::resetBoard() noexcept {
  const std::lock_guard<std::mutex> lock(mutex_);
  bootLocked(Clock::now());
}

void BoardEmulator::unplug() noexcept {
  const std::lock_guard<std::mutex> lock(mutex_);
  plugged_ = false;
  queue_size_ = 0;
  zeroOutputsLocked();  // bus-powered board: no power, no torque
  outputs_enabled_ = configured_ = false;
}

void BoardEmulator::replug() noexcept {
  const std::lock_guard<std::mutex> lock(mutex_);
  plugged_ = true;
  bootLocked(Clock::now());
}

void BoardEmulator::service() noexcept {
  const std::lock_guard<std::mutex> lock(mutex_);
  advanceLocked(Clock::now());
}

void BoardEmulator::setUserForce(const Vec3& force) noexcept {
  const std::lock_guard<std::mutex> lock(mutex_);
  plant_.setUserForce(force);
}

void BoardEmulator::setSceneForce(const Vec3& force) noexcept {
  const std::lock_guard<std::mutex> lock(mutex_);
  plant_.setSceneForce(force);
}

bool BoardEmulator::readUserPoint(Vec3& position, Vec3& velocity) noexcept {
  const std::lock_guard<std::mutex> lock(mutex_);
  return plant_.readUserPoint(position, velocity);
}

BoardEmulator::Snapshot BoardEmulator::snapshot() const noexcept {
  const std::lock_guard<std::mutex> lock(mutex_);
  Snapshot s;
  s.configured = configured_;
  s.outputs_enabled = outputs_enabled_;
  s.commands_applied = commands_applied_;
  s.watchdog_trips = watchdog_trips_;
  s.frames_rejected = rx_stats_.totalRejected();
  s.applied = applied_;
  return s;
}

bool BoardEmulatorControl::attached() const noexcept {
  const std::lock_guard<std::mutex> lock(mutex_);
  return emulator_ != nullptr;
}

void BoardEmulatorControl::attach(BoardEmulator* emulator) noexcept {
  const std::lock_guard<std::mutex> lock(mutex_);
  emulator_ = emulator;
}

bool BoardEmulatorControl::inject(BoardEmulator::Fault fault, int frames, int delay_periods) noexcept {
  const std::lock_guard<std::mutex> lock(mutex_);
  if (emulator_ == nullptr) return false;
  emulator_->inject(fault, frames, delay_periods);
  return true;
}

bool BoardEmulatorControl::unplug() noexcept {
  const std::lock_guard<std::mutex> lock(mutex_);
  if (emulator_ == nullptr) return false;
  emulator_->unplug();
  return true;
}

bool BoardEmulatorControl::replug() noexcept {
  const std::lock_guard<std::mutex> lock(mutex_);
  if (emulator_ == nullptr) return false;
  emulator_->replug();
  return true;
}

bool BoardEmulatorControl::resetBoard() noexcept {
  const std::lock_guard<std::mutex> lock(mutex_);
  if (emulator_ == nullptr) return false;
  emulator_->resetBoard();
  return true;
}

bool BoardEmulatorControl::snapshot(BoardEmulator::Snapshot& out) const noexcept {
  const std::lock_guard<std::mutex> lock(mutex_);
  if (emulator_ == nullptr) return false;
  out = emulator_->snapshot();
  return true;
}

}  // namespace uhaptics
