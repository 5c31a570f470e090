// The host path end to end for each device: its renderer -> ServoLoop (safety stage) -> wire
// protocol -> BoardEmulator -> the device's own simulation, with every fault the emulator injects.
//
// Fault tests drive tick() by hand so that "zero within N periods" is counted in periods, not
// measured in wall time (CI machines are noisy). The threaded tests assert what the loop
// guarantees whatever the machine does (nothing lost, every period counted, zero sent while the
// watchdog is tripped, every trip followed by a resume) and report watchdog trips, which a VM stall
// under load can cause even with a 50-period watchdog, instead of failing on them.
#include <catch2/catch.hpp>

#include <atomic>
#include <chrono>
#include <cmath>
#include <iostream>
#include <limits>
#include <random>
#include <thread>

#include "servo_rig.hpp"
#include "uhaptics/core/fault.hpp"
#include "uhaptics/tools/alloc_probe.hpp"

using namespace uhaptics;
using namespace uhaptics::testing;

namespace {

const DeviceCase& kExo = allDevices()[0];
const DeviceCase& kTau = allDevices()[1];
const DeviceCase& kRhi = allDevices()[2];

// A device rig driven by its own renderer, connected and run for a few periods.
struct RenderedRig {
  std::unique_ptr<DeviceServoRenderer> renderer;
  Rig rig;
  RenderedRig(const DeviceCase& c, const ServoConfig& cfg)
      : renderer(makeDeviceRenderer(c)), rig(c, cfg, renderer.get()) {
    rig.loop.connect();
    const Trace t = run(rig, 20, c.actuators());
    REQUIRE(t.lastAsSent());                // the board applies what the host sent...
    REQUIRE_FALSE(t.zero.back());           // ...and the renderer is commanding something
    REQUIRE(renderer->faults() == 0);
  }
};

// A fault that starves the host of valid STATEs, injected after a device ran normally: the first
// bad period is reported (`first_bad`), the 3-period host watchdog trips two periods later, the
// board drives zero from that period until the loop resumes, and at the end it follows the host
// again.
const ServoEvent& expectZeroWithinWatchdog(const Trace& t, ServoEventKind first_bad) {
  const ServoEvent* bad = find(t.events, first_bad);
  const ServoEvent* trip = find(t.events, ServoEventKind::kHostWatchdog);
  const ServoEvent* resumed = find(t.events, ServoEventKind::kResumed);
  REQUIRE(bad != nullptr);
  REQUIRE(trip != nullptr);
  REQUIRE(resumed != nullptr);
  CHECK(trip->tick - bad->tick == 2);
  CHECK(t.firstZeroTick() == static_cast<std::int64_t>(trip->tick));
  CHECK(t.zeroThroughout(trip->tick, resumed->tick - 1));
  CHECK(t.lastAsSent());
  CHECK_FALSE(t.zero.back());
  return *bad;
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

// A board that samples when a COMMAND arrives: the emulator's STATEs with each sample time set to
// the answer's board time, so the sample age is 0 whatever the host's phase.
class SampleOnRequestBoard final : public Transport {
 public:
  explicit SampleOnRequestBoard(Transport& board) : board_(board) {}
  TransportStatus send(const std::uint8_t* data, std::size_t size, int timeout_us) noexcept override {
    return board_.send(data, size, timeout_us);
  }
  TransportStatus receive(std::uint8_t* buffer, std::size_t capacity, std::size_t& n, int timeout_us) noexcept override {
    const TransportStatus s = board_.receive(buffer, capacity, n, timeout_us);
    wire::Frame f;
    if (s != TransportStatus::kOk || wire::decode(buffer, n, f) != wire::Reject::kNone || f.type != wire::MessageType::kState)
      return s;
    for (int i = 0; i < f.state.count; ++i) f.state.sample_time_us[i] = f.state.board_time_us;
    n = wire::encode(f, buffer, capacity);
    return s;
  }
  bool reconnect() noexcept override { return board_.reconnect(); }
  const char* describe() const noexcept override { return "sample-on-request board"; }

 private:
  Transport& board_;
};

}  // namespace

TEST_CASE("the emulated device rests until the host first enables its outputs, then moves", "[servo][e2e]") {
  // The TAU with no torque sinks under gravity: a board's start-up (the handshake, the servo thread's
  // start) must not hand the session a device that has been falling meanwhile.
  const DeviceCase& c = kTau;
  Rig rig(c, handDrivenConfig(c));
  std::vector<double> boot(static_cast<std::size_t>(rig.plant->jointCount())), now(boot.size());
  rig.plant->readJoints(boot.data());
  rig.loop.connect();
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  rig.board.service();  // 50 of the board's sample periods, outputs never enabled
  rig.plant->readJoints(now.data());
  CHECK(now == boot);
  run(rig, 50, c.actuators());  // zero efforts, outputs enabled: gravity acts from now on
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  rig.board.service();
  rig.plant->readJoints(now.data());
  double moved = 0.0;
  for (std::size_t i = 0; i < boot.size(); ++i) moved = std::max(moved, std::abs(now[i] - boot[i]));
  CHECK(moved > 1e-3);  // rad: the unpowered TAU has sagged
}

TEST_CASE("phase lock: a board that samples on request is left alone, its period not stretched", "[servo][e2e]") {
  const DeviceCase& c = kTau;
  ServoConfig cfg = handDrivenConfig(c);
  cfg.watchdog_periods = 50;
  const auto renderer = makeDeviceRenderer(c);
  Rig rig(c, cfg, renderer.get());  // its loop is not used: the one below talks through the wrapper
  SampleOnRequestBoard board(rig.board);
  ServoLoop loop(c.device(), board, cfg, renderer.get());
  loop.connect();
  loop.start();
  std::this_thread::sleep_for(std::chrono::milliseconds(600));  // 600 periods: past the 200 it may try
  loop.stop();
  const std::string summary = loop.summary();
  INFO(summary);
  CHECK(loop.sampleAgeUs() < 1.0);
  CHECK(summary.find("given up") != std::string::npos);  // without the give-up: +20 us every period
  if (kRealTimeBounds) CHECK(loop.timing().period.p50_us == Approx(1000.0).epsilon(0.01));
}

TEST_CASE("normal operation: each device through its renderer at 1 kHz for 3 s, nothing lost", "[servo][e2e]") {
  for (const DeviceCase& c : allDevices()) {
    ServoConfig cfg = handDrivenConfig(c);
    cfg.rate_hz = 1000.0;        // the 1 kHz for every device (the exoskeleton's USB runs 500 Hz)
    cfg.realtime = true;         // used when permitted; the note says which
    cfg.watchdog_periods = 50;   // generous: a noisy shared CI machine must not trip it
    cfg.board_watchdog_us = 100000;  // (stalls of 10+ ms were seen on a loaded 2-core CI machine)
    const auto renderer = makeDeviceRenderer(c);
    Rig rig(c, cfg, renderer.get());
    const wire::DeviceInfo info = rig.loop.connect();
    CHECK(info.selected_version == wire::kProtocolVersion);
    CHECK(info.joint_count == c.device().joints);
    CHECK(info.sample_rate_hz == c.spec.sample_rate_hz);
    const std::string note = rig.loop.start();

    // The graphics side: reads, event draining, no requests (the renderer commands the device).
    std::vector<double> low(8, 1e9), high(8, -1e9);
    std::uint64_t snapshots = 0, non_finite = 0, zero_commands = 0, tripped_snapshots = 0, tripped_not_zero = 0;
    std::uint64_t trip_events = 0, resume_events = 0;
    const auto count_events = [&] {
      for (const ServoEvent& e : drain(rig.loop)) {
        trip_events += e.kind == ServoEventKind::kHostWatchdog;
        resume_events += e.kind == ServoEventKind::kResumed;
      }
    };
    const auto t0 = std::chrono::steady_clock::now();
    while (std::chrono::steady_clock::now() - t0 < std::chrono::seconds(3)) {
      DeviceSnapshot s;
      if (rig.loop.latest(s)) {
        ++snapshots;
        for (int i = 0; i < s.joints; ++i) {
          non_finite += !std::isfinite(s.position[i]);
          low[i] = std::min(low[i], s.position[i]);
          high[i] = std::max(high[i], s.position[i]);
        }
        bool zero = true;
        for (int i = 0; i < s.actuators; ++i) zero = zero && s.command_sent[i] == 0.0;
        zero_commands += zero;
        tripped_snapshots += s.host_watchdog_tripped;
        tripped_not_zero += s.host_watchdog_tripped && !zero;
      }
      count_events();
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    rig.loop.stop();
    count_events();
    const ServoCounters k = rig.loop.counters();
    const TimingReport timing = rig.loop.timing();
    std::cout << c.name() << " through its renderer at 1 kHz:\n" << rig.loop.summary() << "\n" << note << "\n\n";

    INFO(c.name() << "\n" << rig.loop.summary());
    CHECK(k.frames_lost == 0);
    CHECK(k.frames_rejected == 0);
    CHECK(k.duplicates == 0);
    CHECK(k.states_missing == 0);
    CHECK(k.clamped_ticks == 0);          // the renderers stay inside the limits by themselves
    CHECK(k.non_finite_commands == 0);
    CHECK(k.states == k.ticks);
    CHECK(timing.samples + 1 == k.ticks);
    CHECK(snapshots > 10);
    CHECK(non_finite == 0);
    // What the loop guarantees under any load: a trip (here only a stalled servo thread can cause
    // one) is counted, zero goes out while it lasts, and the loop resumes after each.
    CHECK(k.events_dropped == 0);
    CHECK(trip_events == k.host_watchdog_trips);
    CHECK(resume_events == k.host_watchdog_trips);
    CHECK(tripped_not_zero == 0);
    if (k.host_watchdog_trips > 0) {
      std::cout << "  reported, not failed: " << k.host_watchdog_trips << " host watchdog trip(s), " << k.loop_stalls
                << " loop stall(s) on this machine; " << tripped_snapshots << " snapshot(s) read while tripped, all zero\n";
      WARN(c.name() << ": " << k.host_watchdog_trips << " host watchdog trip(s) (servo thread stalled), each zeroed and resumed");
    }
    if (kRealTimeBounds && k.host_watchdog_trips == 0) {
      // A trip zeroes the TAU's gravity compensation and drops the tool toward its end stops, far
      // from where the renderer was holding it; what it reports then is not under test here.
      // Without trips it must not fault.
      CHECK(renderer->faults() == 0);
      // At least half the nominal cycles in 3 s: a bound only a broken loop (not a busy machine) fails.
      CHECK(static_cast<double>(k.ticks) > 0.5 * 3.0 * cfg.rate_hz);
      CHECK(timing.period.p50_us == Approx(1000.0).epsilon(0.5));
      CHECK(zero_commands < snapshots / 10);  // the renderer was driving the device, not idling
      // The phase lock put COMMANDs in the middle of the board's sample period (whatever the phase
      // the two clocks started with): the command delay is one period with room for jitter.
      const double sample_period_us = 1e6 / c.spec.sample_rate_hz;
      CHECK(std::abs(rig.loop.sampleAgeUs() - 0.5 * sample_period_us) < 0.2 * sample_period_us);
      CHECK(rig.loop.summary().find("given up") == std::string::npos);
    }
    // The simulation moved: the exoskeleton's finger flexes by itself; the TAU and the RHI move
    // under the renderer's torques against the hand (at least an encoder count on some joint).
    double travel = 0.0;
    for (int i = 0; i < c.device().joints; ++i) travel = std::max(travel, high[i] - low[i]);
    std::cout << "  largest joint travel " << travel << " (rad or m)\n\n";
    CHECK(travel > 1e-3);
    const auto board = rig.board.snapshot();
    CHECK(board.commands_applied >= k.ticks);
    CHECK(board.frames_rejected == 0);
    if (k.loop_stalls == 0) CHECK(board.watchdog_trips == 0);  // a stall longer than the board's 100 ms may trip it too
    for (int i = 0; i < c.actuators(); ++i) CHECK(board.applied[i] == 0.0);  // stop() leaves zero
  }
}

TEST_CASE("dropped frames: host watchdog commands zero within its periods, then resumes", "[servo][fault]") {
  for (const DeviceCase& c : allDevices()) {
    INFO(c.name());
    RenderedRig r(c, handDrivenConfig(c));
    r.rig.board.inject(BoardEmulator::Fault::kDrop, 10);
    const Trace t = run(r.rig, 30, c.actuators());
    expectZeroWithinWatchdog(t, ServoEventKind::kStateMissing);
    const ServoEvent* lost = find(t.events, ServoEventKind::kFramesLost);
    REQUIRE(lost != nullptr);
    CHECK(lost->value == 10);
    CHECK(r.rig.loop.counters().frames_lost == 10);
  }
}

TEST_CASE("a single dropped frame is tolerated without zeroing", "[servo][fault]") {
  for (const DeviceCase& c : allDevices()) {
    INFO(c.name());
    RenderedRig r(c, handDrivenConfig(c));
    r.rig.board.inject(BoardEmulator::Fault::kDrop, 1);
    const Trace t = run(r.rig, 10, c.actuators());
    CHECK(find(t.events, ServoEventKind::kHostWatchdog) == nullptr);
    CHECK(t.firstZeroTick() < 0);
    CHECK(r.rig.loop.counters().frames_lost == 1);
  }
}

TEST_CASE("corrupted frames are rejected by CRC, counted, and zero follows", "[servo][fault]") {
  for (const DeviceCase& c : allDevices()) {
    INFO(c.name());
    RenderedRig r(c, handDrivenConfig(c));
    r.rig.board.inject(BoardEmulator::Fault::kCorrupt, 10);
    const Trace t = run(r.rig, 30, c.actuators());
    const ServoEvent& rejected = expectZeroWithinWatchdog(t, ServoEventKind::kFrameRejected);
    CHECK(static_cast<wire::Reject>(rejected.detail) == wire::Reject::kBadCrc);
    const ServoCounters k = r.rig.loop.counters();
    CHECK(k.rejected_by_reason[static_cast<std::size_t>(wire::Reject::kBadCrc)] == 10);
    CHECK(k.frames_rejected == 10);
    CHECK(k.frames_lost == 10);
  }
}

TEST_CASE("duplicated frames are discarded by sequence number", "[servo][fault]") {
  for (const DeviceCase& c : allDevices()) {
    INFO(c.name());
    RenderedRig r(c, handDrivenConfig(c));
    r.rig.board.inject(BoardEmulator::Fault::kDuplicate, 5);
    const Trace t = run(r.rig, 20, c.actuators());
    const ServoCounters k = r.rig.loop.counters();
    CHECK(k.duplicates == 5);
    CHECK(k.frames_lost == 0);
    CHECK(k.host_watchdog_trips == 0);
    CHECK(t.firstZeroTick() < 0);
    CHECK(find(t.events, ServoEventKind::kDuplicateFrame) != nullptr);
  }
}

TEST_CASE("delayed frames trip the watchdog, the backlog is drained, nothing is lost", "[servo][fault]") {
  for (const DeviceCase& c : allDevices()) {
    INFO(c.name());
    RenderedRig r(c, handDrivenConfig(c));
    r.rig.board.inject(BoardEmulator::Fault::kDelay, 3, 6);  // held 6 periods > the 3-period watchdog
    const Trace t = run(r.rig, 40, c.actuators());
    expectZeroWithinWatchdog(t, ServoEventKind::kStateMissing);
    CHECK(r.rig.loop.counters().frames_lost == 0);
  }
}

TEST_CASE("board reset: reported, zero, handshake again, resume", "[servo][fault]") {
  for (const DeviceCase& c : allDevices()) {
    INFO(c.name());
    RenderedRig r(c, handDrivenConfig(c));
    r.rig.board.resetBoard();
    CHECK(r.rig.allZero(c.actuators()));  // a rebooting board drives nothing
    const Trace t = run(r.rig, 10, c.actuators());
    const ServoEvent* reset = find(t.events, ServoEventKind::kBoardReset);
    const ServoEvent* resumed = find(t.events, ServoEventKind::kResumed);
    REQUIRE(reset != nullptr);
    REQUIRE(resumed != nullptr);
    CHECK(reset->tick - t.start_tick <= 2);
    CHECK(resumed->tick - reset->tick == 1);
    CHECK(t.zeroThroughout(t.start_tick, reset->tick));
    CHECK(r.rig.loop.counters().board_resets == 1);
    CHECK(t.lastAsSent());
    CHECK_FALSE(t.zero.back());
  }
}

TEST_CASE("unplug and replug: reported, zero, reconnect, resume", "[servo][fault]") {
  for (const DeviceCase& c : allDevices()) {
    INFO(c.name());
    RenderedRig r(c, handDrivenConfig(c));
    r.rig.board.unplug();
    Trace t = run(r.rig, 20, c.actuators());
    REQUIRE(find(t.events, ServoEventKind::kDisconnected) != nullptr);
    CHECK(find(t.events, ServoEventKind::kDisconnected)->tick == t.start_tick + 1);
    DeviceSnapshot s;
    r.rig.loop.latest(s);
    CHECK(s.link == LinkState::kDisconnected);
    for (int i = 0; i < c.actuators(); ++i) CHECK(s.command_sent[i] == 0.0);
    CHECK(t.zeroThroughout(t.start_tick, t.ticks.back()));
    CHECK(find(t.events, ServoEventKind::kReconnected) == nullptr);

    r.rig.board.replug();
    // reconnect_interval_ms 5: an attempt every 3 periods at 500 Hz, every 5 at 1 kHz.
    t = run(r.rig, 12, c.actuators());
    const ServoEvent* back = find(t.events, ServoEventKind::kReconnected);
    const ServoEvent* resumed = find(t.events, ServoEventKind::kResumed);
    REQUIRE(back != nullptr);
    REQUIRE(resumed != nullptr);
    CHECK(back->tick - t.start_tick <= static_cast<std::uint64_t>(std::ceil(5e-3 * c.spec.servo_rate_hz)));
    CHECK(resumed->tick == back->tick + 1);
    r.rig.loop.latest(s);
    CHECK(s.link == LinkState::kRunning);
    CHECK(t.lastAsSent());
    CHECK_FALSE(t.zero.back());
    const ServoCounters k = r.rig.loop.counters();
    CHECK(k.disconnects == 1);
    CHECK(k.reconnects == 1);
  }
}

TEST_CASE("dead host: the board watchdog zeroes the outputs and says so", "[servo][fault]") {
  for (const DeviceCase& c : allDevices()) {
    INFO(c.name());
    ServoConfig cfg = handDrivenConfig(c);
    cfg.board_watchdog_us = c.spec.board_watchdog_us;  // the parameter file's value
    RenderedRig r(c, cfg);
    std::this_thread::sleep_for(std::chrono::microseconds(3 * c.spec.board_watchdog_us));
    r.rig.board.service();
    auto board = r.rig.board.snapshot();
    CHECK(board.watchdog_trips == 1);
    CHECK_FALSE(board.outputs_enabled);
    CHECK(r.rig.allZero(c.actuators()));
    // The host comes back: the board reports the expiry, then follows commands again.
    const Trace t = run(r.rig, 3, c.actuators());
    const ServoEvent* err = find(t.events, ServoEventKind::kBoardError);
    REQUIRE(err != nullptr);
    CHECK(static_cast<wire::BoardError>(err->detail) == wire::BoardError::kWatchdogExpired);
    CHECK(t.lastAsSent());
    CHECK_FALSE(t.zero.back());
  }
}

TEST_CASE("a stalled servo thread is detected and zero is commanded", "[servo][fault]") {
  struct StallingRenderer final : ServoRenderer {
    std::atomic<bool> stall{false};
    void render(const DeviceSnapshot&, const EffortRequest& r, double* out) noexcept override {
      if (stall.exchange(false)) std::this_thread::sleep_for(std::chrono::milliseconds(20));
      for (int i = 0; i < r.count; ++i) out[i] = r.effort[i];
    }
  } renderer;
  ServoConfig cfg = handDrivenConfig(kRhi);
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
    Rig rig(kTau, handDrivenConfig(kTau), &renderer);
    rig.loop.connect();
    const Trace t = run(rig, 5, 6);
    const ServoEvent* e = find(t.events, ServoEventKind::kNonFiniteCommand);
    REQUIRE(e != nullptr);
    CHECK(e->detail == 2);
    for (int i = 0; i < 6; ++i) CHECK(rig.applied(i) == 0.0);
    CHECK(rig.loop.counters().non_finite_commands == 5);  // every tick (each has a fresh state)
  }
  SECTION("over the limit -> scaled into the box, direction kept, each channel logged once") {
    Rig rig(kRhi, handDrivenConfig(kRhi));
    rig.loop.connect();
    EffortRequest r;
    r.count = 4;
    r.effort = {6.0, -3.0, 0.5, 2.0};  // limits [3, 3, 1, 1]: channels 0 and 3 are 2x over
    rig.loop.request(r);
    const Trace t = run(rig, 10, 4);
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
  SECTION("a device renderer's command pushed past the limits is scaled into them before it leaves") {
    for (const DeviceCase& c : allDevices()) {
      INFO(c.name());
      RenderedRig rr(c, handDrivenConfig(c));
      rr.rig.loop.request(constantRequest(c, 3.0));  // three times each limit on top of the renderer
      const Trace t = run(rr.rig, 10, c.actuators());
      const auto board = rr.rig.board.snapshot();
      double largest = 0.0;  // of |applied| / limit: the box is touched, never left
      for (int i = 0; i < c.actuators(); ++i) largest = std::max(largest, std::abs(board.applied[i]) / c.limit(i));
      CHECK(largest == Approx(1.0).epsilon(1e-6));  // float32 on the wire
      CHECK(t.lastAsSent());
      CHECK(find(t.events, ServoEventKind::kClamped) != nullptr);
      CHECK(rr.rig.loop.counters().clamped_ticks == 10);
    }
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
    Rig rig(kTau, handDrivenConfig(kTau), nullptr, newer);
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
    exo_board.device = kExo.type;
    BoardEmulator board(exo_board, plant);
    ServoLoop loop(kTau.device(), board, handDrivenConfig(kTau));
    CHECK_THROWS_WITH(loop.connect(), Catch::Contains("reports device 'finger exoskeleton' (code 1)") &&
                                          Catch::Contains("expected 'TAU'"));
  }
  SECTION("no answer") {
    SilentTransport silent;
    ServoConfig cfg = handDrivenConfig(kTau);
    cfg.handshake_timeout_ms = 20;
    ServoLoop loop(kTau.device(), silent, cfg);
    CHECK_THROWS_WITH(loop.connect(), Catch::Contains("no answer to HELLO within 20 ms"));
    CHECK_THROWS_WITH(loop.start(), Catch::Contains("connect() first"));
  }
  SECTION("invalid configuration") {
    ServoConfig cfg = handDrivenConfig(kTau);
    cfg.rate_hz = 100.0;
    SilentTransport silent;
    CHECK_THROWS_WITH(ServoLoop(kTau.device(), silent, cfg), Catch::Contains("500 .. 10000 Hz"));
    cfg.rate_hz = 20000.0;
    CHECK_THROWS_AS(ServoLoop(kTau.device(), silent, cfg), Error);
    DeviceDescriptor d = kRhi.device();
    d.effort_limit[3] = 0.0;
    CHECK_THROWS_WITH(ServoLoop(d, silent, handDrivenConfig(kRhi)), Catch::Contains("effort limit of actuator 3"));
  }
}

TEST_CASE("servo ticks allocate nothing, through each device's renderer and every fault", "[servo][alloc]") {
  for (const DeviceCase& c : allDevices()) {
    INFO(c.name());
    RenderedRig r(c, handDrivenConfig(c));
    std::uint64_t allocations = 0;
    {
      tools::AllocationScope scope;
      for (int k = 0; k < 300; ++k) r.rig.loop.tick();
      r.rig.board.inject(BoardEmulator::Fault::kDrop, 5);
      for (int k = 0; k < 20; ++k) r.rig.loop.tick();
      r.rig.board.inject(BoardEmulator::Fault::kCorrupt, 5);
      for (int k = 0; k < 20; ++k) r.rig.loop.tick();
      r.rig.board.inject(BoardEmulator::Fault::kDuplicate, 5);
      for (int k = 0; k < 20; ++k) r.rig.loop.tick();
      r.rig.board.resetBoard();
      for (int k = 0; k < 20; ++k) r.rig.loop.tick();
      allocations = scope.count();
    }
    CHECK(allocations == 0);
    const ServoCounters k = r.rig.loop.counters();
    CHECK(k.board_resets == 1);
    CHECK(k.frames_rejected == 5);
    CHECK(r.renderer->faults() == 0);
    const Trace t = run(r.rig, 1, c.actuators());
    CHECK(t.lastAsSent());
  }
}
