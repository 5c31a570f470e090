#pragma once
// The host path wired end to end for the servo tests: the device's renderer -> ServoLoop (safety
// stage) -> wire protocol -> BoardEmulator -> the device's own simulation (its plant, devices/<device>/backend), with
// the channel layout, limits and USB identity read from the device's parameter file.
#include <memory>
#include <string>
#include <vector>

#include "device_servo_renderers.hpp"
#include "uhaptics/backends/board_catalog.hpp"
#include "uhaptics/backends/board_emulator.hpp"
#include "uhaptics/backends/tau_plant.hpp"  // TauBoardPlant with its own options (joint_io_test)
#include "uhaptics/backends/servo_loop.hpp"
#include "uhaptics/core/sanitized_build.hpp"

namespace uhaptics::testing {

inline const std::string kParamsDir = UHAPTICS_PARAMS_DIR;

// Sanitizer builds run the servo tick (renderer + the emulated board's simulation) several times
// slower than the optimized build; on a loaded 2-core machine the TAU's then overruns 1 ms. Bounds
// that depend on keeping real time are asserted in optimized builds and only printed under them.
inline constexpr bool kRealTimeBounds = !kSanitizedBuild;

struct DeviceCase {
  const DeviceDefinition* definition;
  wire::DeviceType type;
  BoardSpec spec;
  const DeviceDescriptor& device() const { return spec.descriptor; }
  const std::string& name() const { return spec.descriptor.name; }
  int actuators() const { return spec.descriptor.actuators; }
  double limit(int i) const { return spec.descriptor.effort_limit[static_cast<std::size_t>(i)]; }
};
inline DeviceCase deviceCase(const std::string& name) {
  const DeviceDefinition& d = findDevice(name);
  return {&d, wire::DeviceType{d.wire_code}, boardSpec(d, kParamsDir)};
}
/// Every registered device.
inline const std::vector<DeviceCase>& allDevices() {
  static const std::vector<DeviceCase> all = [] {
    std::vector<DeviceCase> cases;
    for (const DeviceDefinition* d : deviceDefinitions()) cases.push_back(deviceCase(d->name));
    return cases;
  }();
  return all;
}

inline std::unique_ptr<DeviceServoRenderer> makeDeviceRenderer(const DeviceCase& c) {
  return uhaptics::makeDeviceRenderer(*c.definition, kParamsDir);
}

/// Settings for hand-driven ticks: a 3-period host watchdog, quick reconnects, no SCHED_FIFO.
inline ServoConfig handDrivenConfig(const DeviceCase& c) {
  ServoConfig cfg;
  cfg.rate_hz = c.spec.servo_rate_hz;
  cfg.watchdog_periods = 3;
  cfg.reconnect_interval_ms = 5;
  cfg.realtime = false;
  // Hand-driven ticks can be descheduled for milliseconds on a loaded machine: keep the board's
  // watchdog out of the fault tests (except the one about it) so that they count periods exactly.
  cfg.board_watchdog_us = 200000;
  return cfg;
}

// Plant + board + host loop (+ renderer), wired together.
struct Rig {
  std::unique_ptr<BoardPlant> plant;
  BoardEmulator board;
  ServoLoop loop;
  Rig(const DeviceCase& c, const ServoConfig& cfg, ServoRenderer* renderer = nullptr, BoardEmulator::Config board_cfg = {})
      : plant(c.definition->make_plant(c.spec.params_path)),
        board(withDevice(board_cfg, c), *plant),
        loop(c.device(), board, cfg, renderer) {}
  static BoardEmulator::Config withDevice(BoardEmulator::Config b, const DeviceCase& c) {
    b.device = c.type;
    b.sample_rate_hz = c.spec.sample_rate_hz;
    return b;  // no board-side clamp: what reaches the plant is what the host let through
  }
  double applied(int i) const { return board.snapshot().applied[static_cast<std::size_t>(i)]; }
  bool allZero(int actuators) const {
    const auto s = board.snapshot();
    for (int i = 0; i < actuators; ++i)
      if (s.applied[static_cast<std::size_t>(i)] != 0.0) return false;
    return true;
  }
};

inline EffortRequest constantRequest(const DeviceCase& c, double fraction) {
  EffortRequest r;
  r.count = c.actuators();
  for (int i = 0; i < c.actuators(); ++i) r.effort[static_cast<std::size_t>(i)] = fraction * c.limit(i) * (i % 2 ? -1.0 : 1.0);
  return r;
}

inline std::vector<ServoEvent> drain(ServoLoop& loop) {
  std::vector<ServoEvent> events;
  ServoEvent e;
  while (loop.nextEvent(e)) events.push_back(e);
  return events;
}

inline const ServoEvent* find(const std::vector<ServoEvent>& events, ServoEventKind kind) {
  for (const auto& e : events)
    if (e.kind == kind) return &e;
  return nullptr;
}

// Ticks by hand, recording events and, per tick, whether the board drives zero on every actuator
// and whether it drives exactly what the host sent.
struct Trace {
  std::vector<ServoEvent> events;
  std::vector<std::uint64_t> ticks;
  std::vector<bool> zero, as_sent;
  std::uint64_t start_tick = 0;
  std::int64_t firstZeroTick() const {
    for (std::size_t k = 0; k < ticks.size(); ++k)
      if (zero[k]) return static_cast<std::int64_t>(ticks[k]);
    return -1;
  }
  /// Whether the board drove zero at every tick in [from, to].
  bool zeroThroughout(std::uint64_t from, std::uint64_t to) const {
    for (std::size_t k = 0; k < ticks.size(); ++k)
      if (ticks[k] >= from && ticks[k] <= to && !zero[k]) return false;
    return true;
  }
  bool lastAsSent() const { return !as_sent.empty() && as_sent.back(); }
};
inline Trace run(Rig& rig, int ticks, int actuators) {
  Trace t;
  DeviceSnapshot s;
  rig.loop.latest(s);
  t.start_tick = s.tick;
  for (int k = 0; k < ticks; ++k) {
    rig.loop.tick();
    rig.loop.latest(s);
    const auto board = rig.board.snapshot();
    bool zero = true, as_sent = true;
    for (int i = 0; i < actuators; ++i) {
      const auto j = static_cast<std::size_t>(i);
      zero = zero && board.applied[j] == 0.0;
      // The wire carries float32: the board applies the host's value rounded to float.
      as_sent = as_sent && board.applied[j] == static_cast<double>(static_cast<float>(s.command_sent[j]));
    }
    t.ticks.push_back(s.tick);
    t.zero.push_back(zero);
    t.as_sent.push_back(as_sent);
    for (const auto& e : drain(rig.loop)) t.events.push_back(e);
  }
  return t;
}

}  // namespace uhaptics::testing
