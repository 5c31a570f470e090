// The host path end to end: ServoLoop -> wire protocol -> BoardEmulator -> plant, for the three
// devices' channel layouts, with every fault the emulator can inject.
//
// Fault tests drive tick() by hand so that "zero within N periods" is counted in periods, not
// measured in wall time (CI machines are noisy). The threaded tests assert only generous bounds
// (no lost frames, no watchdog trip with a 50-period watchdog) and print the timing figures.
#include <catch2/catch.hpp>

#include <atomic>
#include <chrono>
#include <cmath>
#include <iostream>
#include <limits>
#include <memory>
#include <random>
#include <thread>
#include <vector>

#include "uhaptics/backends/board_catalog.hpp"
#include "uhaptics/backends/board_emulator.hpp"
#include "uhaptics/backends/servo_loop.hpp"
#include "uhaptics/core/fault.hpp"
#include "uhaptics/tools/alloc_probe.hpp"

using namespace uhaptics;

namespace {

struct DeviceCase {
  std::string name;
  wire::DeviceType type;
  int joints;
  int actuators;
  std::array<double, wire::kMaxChannels> limits;
  double rate_hz;
  DeviceDescriptor descriptor;
};
// The three boards' channel layouts, limits and rates (board_catalog.hpp, from DESIGN.md).
DeviceCase fromCatalog(wire::DeviceType type) {
  const BoardDefaults b = boardDefaults(type);
  const DeviceDescriptor& d = b.descriptor;
  return {d.name, d.type, d.joints, d.actuators, d.effort_limit, b.servo_rate_hz, d};
}
const DeviceCase kExo = fromCatalog(wire::DeviceType::kExoFinger);
const DeviceCase kTau = fromCatalog(wire::DeviceType::kTau);
const DeviceCase kRhi = fromCatalog(wire::DeviceType::kRhiPlanar);

DeviceDescriptor descriptorFor(const DeviceCase& c) { return c.descriptor; }

ServoConfig configFor(const DeviceCase& c) {
  ServoConfig cfg;
  cfg.rate_hz = c.rate_hz;
  cfg.watchdog_periods = 3;
  cfg.reconnect_interval_ms = 5;
  cfg.realtime = false;
  // Hand-driven ticks can be descheduled for milliseconds on a loaded machine: keep the board's
  // watchdog out of the fault tests (except the one about it) so that they count periods exactly.
  cfg.board_watchdog_us = 200000;
  return cfg;
}

// Plant + board + host loop, wired together.
struct Rig {
  LinearTestPlant plant;
  BoardEmulator board;
  ServoLoop loop;
  Rig(const DeviceCase& c, const ServoConfig& cfg, ServoRenderer* renderer = nullptr,
      BoardEmulator::Config board_cfg = {})
      : plant(LinearTestPlant::Params{c.joints, c.actuators}),
        board(withDevice(board_cfg, c), plant),
        loop(descriptorFor(c), board, cfg, renderer) {}
  static BoardEmulator::Config withDevice(BoardEmulator::Config b, const DeviceCase& c) {
    b.device = c.type;
    return b;  // no board-side clamp: what reaches the plant is what the host let through
  }
  double applied(int i) const { return board.snapshot().applied[i]; }
};

EffortRequest constantRequest(const DeviceCase& c, double fraction) {
  EffortRequest r;
  r.count = c.actuators;
  for (int i = 0; i < c.actuators; ++i) r.effort[i] = fraction * c.limits[i] * (i % 2 ? -1.0 : 1.0);
  return r;
}

std::vector<ServoEvent> drain(ServoLoop& loop) {
  std::vector<ServoEvent> events;
  ServoEvent e;
  while (loop.nextEvent(e)) events.push_back(e);
  return events;
}

const ServoEvent* find(const std::vector<ServoEvent>& events, ServoEventKind kind) {
  for (const auto& e : events)
    if (e.kind == kind) return &e;
  return nullptr;
}

// Ticks by hand, recording events and the first tick at which the board drives zero.
struct Trace {
  std::vector<ServoEvent> events;
  std::int64_t first_zero_tick = -1;
  std::uint64_t start_tick = 0;
};
Trace run(Rig& rig, int ticks) {
  Trace t;
  DeviceSnapshot s;
  rig.loop.latest(s);
  t.start_tick = s.tick;
  for (int k = 0; k < ticks; ++k) {
    rig.loop.tick();
    rig.loop.latest(s);
    if (t.first_zero_tick < 0 && rig.applied(0) == 0.0) t.first_zero_tick = static_cast<std::int64_t>(s.tick);
    for (const auto& e : drain(rig.loop)) t.events.push_back(e);
  }
  return t;
}

void settle(Rig& rig, const DeviceCase& c, double fraction = 0.5) {
  rig.loop.connect();
  rig.loop.request(constantRequest(c, fraction));
  run(rig, 5);
  REQUIRE(rig.applied(0) == Approx(fraction * c.limits[0]));
}

class SilentTransport final : public Transport {
 public:
  TransportStatus send(const std::uint8_t*, std::size_t, int) noexcept override { return TransportStatus::kOk; }
  TransportStatus receive(std::uint8_t*, std::size_t, std::size_t& n, int) noexcept override {
    n = 0;
    return TransportStatus::kTimeout;
  }
  bool reconnect() noexcept override { return false; }
  const char* describe() const noexcept override { return "silent test transport"; }
};

}  // namespace

TEST_CASE("normal operation: each device at its servo rate for 2 s, nothing lost", "[servo][e2e]") {
  for (const DeviceCase* c : {&kExo, &kTau, &kRhi}) {
    ServoConfig cfg = configFor(*c);
    cfg.realtime = true;         // used when permitted; the note says which
    cfg.watchdog_periods = 50;   // generous: a noisy shared CI machine must not trip it
    cfg.board_watchdog_us = 100000;  // (stalls of 10+ ms were seen on a loaded 2-core CI machine)
    Rig rig(*c, cfg);
    const wire::DeviceInfo info = rig.loop.connect();
    CHECK(info.selected_version == wire::kProtocolVersion);
    CHECK(info.joint_count == c->joints);
    const std::string note = rig.loop.start();

    // The graphics side: 1 kHz-ish requests (sinusoids within limits), reads, event draining.
    double max_position = 0.0;
    std::uint64_t snapshots = 0, non_finite = 0;
    const auto t0 = std::chrono::steady_clock::now();
    while (std::chrono::steady_clock::now() - t0 < std::chrono::seconds(2)) {
      const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      EffortRequest r;
      r.count = c->actuators;
      for (int i = 0; i < c->actuators; ++i) r.effort[i] = 0.6 * c->limits[i] * std::sin(2 * M_PI * 2.0 * t + i);
      rig.loop.request(r);
      DeviceSnapshot s;
      if (rig.loop.latest(s)) {
        ++snapshots;
        for (int i = 0; i < s.joints; ++i) {
          non_finite += !std::isfinite(s.position[i]);
          max_position = std::max(max_position, std::abs(s.position[i]));
        }
      }
      drain(rig.loop);
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    rig.loop.stop();
    const ServoCounters k = rig.loop.counters();
    const TimingReport timing = rig.loop.timing();
    std::cout << rig.loop.summary() << "\n" << note << "\n\n";

    INFO(rig.loop.summary());
    CHECK(k.frames_lost == 0);
    CHECK(k.frames_rejected == 0);
    CHECK(k.duplicates == 0);
    CHECK(k.states_missing == 0);
    CHECK(k.host_watchdog_trips == 0);
    CHECK(k.clamped_ticks == 0);
    CHECK(k.states == k.ticks);
    // At least half the nominal cycles in 2 s: a bound only a broken loop (not a busy machine) fails.
    CHECK(static_cast<double>(k.ticks) > 0.5 * 2.0 * c->rate_hz);
    CHECK(timing.samples + 1 == k.ticks);
    CHECK(timing.period.p50_us == Approx(1e6 / c->rate_hz).epsilon(0.5));
    CHECK(snapshots > 100);
    CHECK(non_finite == 0);
    CHECK(max_position > 0.0);  // the plant moved under the commanded efforts
    const auto board = rig.board.snapshot();
    CHECK(board.commands_applied >= k.ticks);
    CHECK(board.frames_rejected == 0);
    CHECK(board.watchdog_trips == 0);
    for (int i = 0; i < c->actuators; ++i) CHECK(board.applied[i] == 0.0);  // stop() leaves zero
  }
}

TEST_CASE("dropped frames: host watchdog commands zero within its periods, then resumes", "[servo][fault]") {
  Rig rig(kTau, configFor(kTau));
  settle(rig, kTau);
  rig.board.inject(BoardEmulator::Fault::kDrop, 10);
  const Trace t = run(rig, 30);
  const ServoEvent* missing = find(t.events, ServoEventKind::kStateMissing);
  const ServoEvent* trip = find(t.events, ServoEventKind::kHostWatchdog);
  REQUIRE(missing != nullptr);
  REQUIRE(trip != nullptr);
  // Watchdog of 3 periods: the third period without a STATE sends zero.
  CHECK(trip->tick - missing->tick == 2);
  CHECK(t.first_zero_tick == static_cast<std::int64_t>(trip->tick));
  const ServoEvent* lost = find(t.events, ServoEventKind::kFramesLost);
  REQUIRE(lost != nullptr);
  CHECK(lost->value == 10);
  CHECK(rig.loop.counters().frames_lost == 10);
  CHECK(find(t.events, ServoEventKind::kResumed) != nullptr);
  CHECK(rig.applied(0) == Approx(0.5 * kTau.limits[0]));
}

TEST_CASE("a single dropped frame is tolerated without zeroing", "[servo][fault]") {
  Rig rig(kRhi, configFor(kRhi));
  settle(rig, kRhi);
  rig.board.inject(BoardEmulator::Fault::kDrop, 1);
  const Trace t = run(rig, 10);
  CHECK(find(t.events, ServoEventKind::kHostWatchdog) == nullptr);
  CHECK(t.first_zero_tick < 0);
  CHECK(rig.loop.counters().frames_lost == 1);
}

TEST_CASE("corrupted frames are rejected by CRC, counted, and zero follows", "[servo][fault]") {
  Rig rig(kRhi, configFor(kRhi));
  settle(rig, kRhi);
  rig.board.inject(BoardEmulator::Fault::kCorrupt, 10);
  const Trace t = run(rig, 30);
  const ServoEvent* rejected = find(t.events, ServoEventKind::kFrameRejected);
  REQUIRE(rejected != nullptr);
  CHECK(static_cast<wire::Reject>(rejected->detail) == wire::Reject::kBadCrc);
  const ServoCounters k = rig.loop.counters();
  CHECK(k.rejected_by_reason[static_cast<std::size_t>(wire::Reject::kBadCrc)] == 10);
  CHECK(k.frames_rejected == 10);
  CHECK(k.frames_lost == 10);
  const ServoEvent* trip = find(t.events, ServoEventKind::kHostWatchdog);
  REQUIRE(trip != nullptr);
  CHECK(trip->tick - rejected->tick == 2);
  CHECK(t.first_zero_tick == static_cast<std::int64_t>(trip->tick));
  CHECK(rig.applied(0) == Approx(0.5 * kRhi.limits[0]));
}

TEST_CASE("duplicated frames are discarded by sequence number", "[servo][fault]") {
  Rig rig(kExo, configFor(kExo));
  settle(rig, kExo);
  rig.board.inject(BoardEmulator::Fault::kDuplicate, 5);
  const Trace t = run(rig, 20);
  const ServoCounters k = rig.loop.counters();
  CHECK(k.duplicates == 5);
  CHECK(k.frames_lost == 0);
  CHECK(k.host_watchdog_trips == 0);
  CHECK(t.first_zero_tick < 0);
  CHECK(find(t.events, ServoEventKind::kDuplicateFrame) != nullptr);
}

TEST_CASE("delayed frames trip the watchdog, the backlog is drained, nothing is lost", "[servo][fault]") {
  Rig rig(kTau, configFor(kTau));
  settle(rig, kTau);
  rig.board.inject(BoardEmulator::Fault::kDelay, 3, 6);  // held 6 periods > the 3-period watchdog
  const Trace t = run(rig, 40);
  const ServoEvent* missing = find(t.events, ServoEventKind::kStateMissing);
  const ServoEvent* trip = find(t.events, ServoEventKind::kHostWatchdog);
  REQUIRE(missing != nullptr);
  REQUIRE(trip != nullptr);
  CHECK(trip->tick - missing->tick == 2);
  CHECK(t.first_zero_tick == static_cast<std::int64_t>(trip->tick));
  CHECK(find(t.events, ServoEventKind::kResumed) != nullptr);
  CHECK(rig.loop.counters().frames_lost == 0);
  CHECK(rig.applied(0) == Approx(0.5 * kTau.limits[0]));
}

TEST_CASE("board reset: reported, zero, handshake again, resume", "[servo][fault]") {
  Rig rig(kRhi, configFor(kRhi));
  settle(rig, kRhi);
  rig.board.resetBoard();
  CHECK(rig.applied(0) == 0.0);  // a rebooting board drives nothing
  const Trace t = run(rig, 10);
  const ServoEvent* reset = find(t.events, ServoEventKind::kBoardReset);
  const ServoEvent* resumed = find(t.events, ServoEventKind::kResumed);
  REQUIRE(reset != nullptr);
  REQUIRE(resumed != nullptr);
  CHECK(reset->tick - t.start_tick <= 2);
  CHECK(resumed->tick - reset->tick == 1);
  CHECK(rig.loop.counters().board_resets == 1);
  CHECK(rig.applied(0) == Approx(0.5 * kRhi.limits[0]));
}

TEST_CASE("unplug and replug: reported, zero, reconnect, resume", "[servo][fault]") {
  Rig rig(kExo, configFor(kExo));
  settle(rig, kExo);
  rig.board.unplug();
  Trace t = run(rig, 20);
  REQUIRE(find(t.events, ServoEventKind::kDisconnected) != nullptr);
  CHECK(find(t.events, ServoEventKind::kDisconnected)->tick == t.start_tick + 1);
  DeviceSnapshot s;
  rig.loop.latest(s);
  CHECK(s.link == LinkState::kDisconnected);
  CHECK(s.command_sent[0] == 0.0);
  CHECK(rig.applied(0) == 0.0);
  CHECK(find(t.events, ServoEventKind::kReconnected) == nullptr);

  rig.board.replug();
  // reconnect_interval_ms 5 at 500 Hz: an attempt every 3 periods.
  t = run(rig, 10);
  const ServoEvent* back = find(t.events, ServoEventKind::kReconnected);
  const ServoEvent* resumed = find(t.events, ServoEventKind::kResumed);
  REQUIRE(back != nullptr);
  REQUIRE(resumed != nullptr);
  CHECK(back->tick - t.start_tick <= 3);
  CHECK(resumed->tick == back->tick + 1);
  rig.loop.latest(s);
  CHECK(s.link == LinkState::kRunning);
  CHECK(rig.applied(0) == Approx(0.5 * kExo.limits[0]));
  const ServoCounters k = rig.loop.counters();
  CHECK(k.disconnects == 1);
  CHECK(k.reconnects == 1);
}

TEST_CASE("dead host: the board watchdog zeroes the outputs and says so", "[servo][fault]") {
  ServoConfig cfg = configFor(kTau);
  cfg.board_watchdog_us = 5000;
  Rig rig(kTau, cfg);
  settle(rig, kTau);
  std::this_thread::sleep_for(std::chrono::milliseconds(30));
  rig.board.service();
  auto board = rig.board.snapshot();
  CHECK(board.watchdog_trips == 1);
  CHECK_FALSE(board.outputs_enabled);
  for (int i = 0; i < kTau.actuators; ++i) CHECK(board.applied[i] == 0.0);
  // The host comes back: the board reports the expiry, then follows commands again.
  const Trace t = run(rig, 3);
  const ServoEvent* err = find(t.events, ServoEventKind::kBoardError);
  REQUIRE(err != nullptr);
  CHECK(static_cast<wire::BoardError>(err->detail) == wire::BoardError::kWatchdogExpired);
  CHECK(rig.applied(0) == Approx(0.5 * kTau.limits[0]));
}

TEST_CASE("a stalled servo thread is detected and zero is commanded", "[servo][fault]") {
  struct StallingRenderer final : ServoRenderer {
    std::atomic<bool> stall{false};
    void render(const DeviceSnapshot&, const EffortRequest& r, double* out) noexcept override {
      if (stall.exchange(false)) std::this_thread::sleep_for(std::chrono::milliseconds(20));
      for (int i = 0; i < r.count; ++i) out[i] = r.effort[i];
    }
  } renderer;
  ServoConfig cfg = configFor(kRhi);
  Rig rig(kRhi, cfg, &renderer);
  rig.loop.connect();
  rig.loop.request(constantRequest(kRhi, 0.3));
  rig.loop.start();
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  renderer.stall = true;
  std::this_thread::sleep_for(std::chrono::milliseconds(150));
  rig.loop.stop();
  const auto events = drain(rig.loop);
  const ServoEvent* stalled = find(events, ServoEventKind::kLoopStalled);
  REQUIRE(stalled != nullptr);
  CHECK(stalled->value >= cfg.watchdog_periods);
  CHECK(find(events, ServoEventKind::kHostWatchdog) != nullptr);
  CHECK(find(events, ServoEventKind::kResumed) != nullptr);
  CHECK(rig.loop.counters().loop_stalls >= 1);
  CHECK(rig.loop.timing().overruns >= 1);
}

TEST_CASE("whatever the renderer produces, commands leave finite and within limits", "[servo][safety]") {
  SECTION("non-finite -> the whole command is zero, the channel is reported") {
    struct NanRenderer final : ServoRenderer {
      void render(const DeviceSnapshot&, const EffortRequest&, double* out) noexcept override {
        for (int i = 0; i < 6; ++i) out[i] = 0.5;
        out[2] = std::numeric_limits<double>::quiet_NaN();
      }
    } renderer;
    Rig rig(kTau, configFor(kTau), &renderer);
    rig.loop.connect();
    const Trace t = run(rig, 5);
    const ServoEvent* e = find(t.events, ServoEventKind::kNonFiniteCommand);
    REQUIRE(e != nullptr);
    CHECK(e->detail == 2);
    for (int i = 0; i < 6; ++i) CHECK(rig.applied(i) == 0.0);
    CHECK(rig.loop.counters().non_finite_commands == 5);  // every tick (each has a fresh state)
  }
  SECTION("over the limit -> scaled into the box, direction kept, each channel logged once") {
    Rig rig(kRhi, configFor(kRhi));
    rig.loop.connect();
    EffortRequest r;
    r.count = 4;
    r.effort = {6.0, -3.0, 0.5, 2.0};  // limits [3, 3, 1, 1]: channels 0 and 3 are 2x over
    rig.loop.request(r);
    const Trace t = run(rig, 10);
    CHECK(rig.applied(0) == Approx(3.0));
    CHECK(rig.applied(1) == Approx(-1.5));
    CHECK(rig.applied(2) == Approx(0.25));
    CHECK(rig.applied(3) == Approx(1.0));
    std::vector<ServoEvent> clamps;
    for (const auto& e : t.events)
      if (e.kind == ServoEventKind::kClamped) clamps.push_back(e);
    REQUIRE(clamps.size() == 2);
    CHECK(clamps[0].detail == 0);
    CHECK(clamps[0].value == 6.0);
    CHECK(clamps[1].detail == 3);
    CHECK(clamps[1].value == 2.0);
    CHECK(describe(clamps[0]).find("actuator 0 requested 6") != std::string::npos);
    CHECK(rig.loop.counters().clamped_ticks == 10);
  }
}

TEST_CASE("enforceEffortLimits: random and extreme inputs always come out inside the box", "[servo][safety]") {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> log_mag(-3.0, 300.0), sign(-1.0, 1.0);
  const double limits[4] = {3, 3, 1, 1};
  for (int trial = 0; trial < 20000; ++trial) {
    double u[4], in[4];
    for (int i = 0; i < 4; ++i) in[i] = u[i] = (sign(rng) < 0 ? -1.0 : 1.0) * std::pow(10.0, log_mag(rng) / 10.0);
    const SafetyOutcome o = enforceEffortLimits(u, 4, limits);
    REQUIRE_FALSE(o.non_finite);
    for (int i = 0; i < 4; ++i) {
      REQUIRE(std::abs(u[i]) <= limits[i]);
      // Direction kept: every channel scaled by the same factor.
      REQUIRE(u[i] == Approx(in[i] * o.scale).epsilon(1e-12).margin(1e-300));
    }
  }
  double inf[2] = {std::numeric_limits<double>::infinity(), 1.0};
  const SafetyOutcome o = enforceEffortLimits(inf, 2, limits);
  CHECK(o.non_finite);
  CHECK(inf[0] == 0.0);
  CHECK(inf[1] == 0.0);
}

TEST_CASE("handshake failures say what is wrong and what to do", "[servo][errors]") {
  SECTION("protocol version mismatch") {
    BoardEmulator::Config newer;
    newer.min_version = 2;
    newer.max_version = 3;
    Rig rig(kTau, configFor(kTau), nullptr, newer);
    REQUIRE_THROWS_AS(rig.loop.connect(), Error);
    try {
      rig.loop.connect();
    } catch (const Error& e) {
      const std::string m = e.what();
      CHECK(m.find("protocol version mismatch") != std::string::npos);
      CHECK(m.find("speaks 2..3") != std::string::npos);
      CHECK(m.find("Update the board's firmware or uhaptics") != std::string::npos);
    }
  }
  SECTION("wrong device on the other end") {
    LinearTestPlant plant(LinearTestPlant::Params{2, 1});
    BoardEmulator::Config exo_board;
    exo_board.device = wire::DeviceType::kExoFinger;
    BoardEmulator board(exo_board, plant);
    ServoLoop loop(descriptorFor(kTau), board, configFor(kTau));
    CHECK_THROWS_WITH(loop.connect(), Catch::Contains("device type 'finger exoskeleton'") &&
                                          Catch::Contains("expected 'TAU'"));
  }
  SECTION("no answer") {
    SilentTransport silent;
    ServoConfig cfg = configFor(kTau);
    cfg.handshake_timeout_ms = 20;
    ServoLoop loop(descriptorFor(kTau), silent, cfg);
    CHECK_THROWS_WITH(loop.connect(), Catch::Contains("no answer to HELLO within 20 ms"));
    CHECK_THROWS_WITH(loop.start(), Catch::Contains("connect() first"));
  }
  SECTION("invalid configuration") {
    ServoConfig cfg = configFor(kTau);
    cfg.rate_hz = 100.0;
    SilentTransport silent;
    CHECK_THROWS_WITH(ServoLoop(descriptorFor(kTau), silent, cfg), Catch::Contains("500 .. 10000 Hz"));
    cfg.rate_hz = 20000.0;
    CHECK_THROWS_AS(ServoLoop(descriptorFor(kTau), silent, cfg), Error);
    DeviceDescriptor d = descriptorFor(kRhi);
    d.effort_limit[3] = 0.0;
    CHECK_THROWS_WITH(ServoLoop(d, silent, configFor(kRhi)), Catch::Contains("effort limit of actuator 3"));
  }
}

TEST_CASE("servo ticks allocate nothing, in normal operation and through every fault", "[servo][alloc]") {
  Rig rig(kTau, configFor(kTau));
  settle(rig, kTau);
  std::uint64_t allocations = 0;
  {
    tools::AllocationScope scope;
    for (int k = 0; k < 500; ++k) rig.loop.tick();
    rig.board.inject(BoardEmulator::Fault::kDrop, 5);
    for (int k = 0; k < 20; ++k) rig.loop.tick();
    rig.board.inject(BoardEmulator::Fault::kCorrupt, 5);
    for (int k = 0; k < 20; ++k) rig.loop.tick();
    rig.board.inject(BoardEmulator::Fault::kDuplicate, 5);
    for (int k = 0; k < 20; ++k) rig.loop.tick();
    rig.board.resetBoard();
    for (int k = 0; k < 20; ++k) rig.loop.tick();
    allocations = scope.count();
  }
  CHECK(allocations == 0);
  const ServoCounters k = rig.loop.counters();
  CHECK(k.board_resets == 1);
  CHECK(k.frames_rejected == 5);
  CHECK(rig.applied(0) == Approx(0.5 * kTau.limits[0]));
}
