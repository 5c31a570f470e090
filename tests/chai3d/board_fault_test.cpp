// Board faults in the middle of a CHAI3D session, for every registered device on the emulated
// board: the application keeps calling the device as CHAI3D does (read the position, set a force,
// about once a millisecond) while the board goes silent, sends corrupt frames or is unplugged, in
// contact (a steady force the device is rendering). Asserted: zero commanded within the host
// watchdog's periods (counted in servo ticks from the loop's events, not measured in wall time),
// the fault reported through the CHAI3D device (getLinkStatus, getLastFault, session statistics),
// no crash, and forces again once the board is back. And after getServoLoop()->stop(), the device
// reports the link as stopped rather than the last reading.
//
// Waits are bounded (10 s, for sanitized builds on a loaded machine); nothing asserts a duration.
#include <catch2/catch.hpp>

#include <chrono>
#include <cmath>
#include <functional>
#include <iostream>
#include <memory>
#include <thread>

#include "chai3d.h"
#include "soak.hpp"
#include "uhaptics/backends/board_emulator.hpp"
#include "uhaptics/chai3d/device_registry.hpp"

using namespace chai3d;
using uhaptics::BoardEmulator;
using uhaptics::LinkStatus;
using uhaptics::ServoEvent;
using uhaptics::ServoEventKind;

namespace {

struct Session {
  std::shared_ptr<uhaptics::BoardEmulatorControl> board = std::make_shared<uhaptics::BoardEmulatorControl>();
  cUhapticsDevicePtr device;
  int watchdog_periods = 0;
  static constexpr int actuators = uhaptics::wire::kMaxChannels;  // applied[] past the device's stays 0

  explicit Session(const std::string& name) {
    uhaptics::DeviceSelection s;
    s.device = name;
    s.backend = "emulated";
    s.joint_io.emulator_control = board;
    watchdog_periods = s.joint_io.servo.watchdog_periods;
    device = uhaptics::adapter::createDevice(s);
  }

  // One cycle of the application's haptic loop: a steady force (a quarter of the device's rated
  // force, along device y and -z: in the plane of the planar devices).
  void appCycle() {
    cVector3d p;
    device->getPosition(p);
    const double f = 0.25 * device->getSpecifications().m_maxLinearForce;
    device->setForceAndTorqueAndGripperForce(cVector3d(0.0, 0.7 * f, -0.7 * f), cVector3d(0, 0, 0), 0.0);
    std::this_thread::sleep_for(std::chrono::microseconds(900));
  }
  // Runs the application until done() (true) or 10 s (false).
  bool runUntil(const std::function<bool()>& done) {
    const auto t0 = std::chrono::steady_clock::now();
    while (std::chrono::steady_clock::now() - t0 < std::chrono::seconds(10)) {
      appCycle();
      if (done()) return true;
    }
    return false;
  }
  BoardEmulator::Snapshot boardState() const {
    BoardEmulator::Snapshot s;
    REQUIRE(board->snapshot(s));
    return s;
  }
  bool boardApplying() const {
    const BoardEmulator::Snapshot s = boardState();
    bool any = false;
    for (int i = 0; i < actuators; ++i) any = any || s.applied[static_cast<std::size_t>(i)] != 0.0;
    return s.outputs_enabled && any;
  }
  bool boardZero() const {
    const BoardEmulator::Snapshot s = boardState();
    for (int i = 0; i < actuators; ++i)
      if (s.applied[static_cast<std::size_t>(i)] != 0.0) return false;
    return true;
  }
  bool linkRunning() {
    return device->getLinkStatus() == LinkStatus::kRunning && device->getLastFault() == uhaptics::Fault::kNone;
  }
  std::vector<ServoEvent> events() {
    std::vector<ServoEvent> out;
    ServoEvent e;
    while (device->getServoLoop()->nextEvent(e)) out.push_back(e);
    return out;
  }
};

const ServoEvent* first(const std::vector<ServoEvent>& events, ServoEventKind kind, std::uint64_t after = 0) {
  for (const ServoEvent& e : events)
    if (e.kind == kind && e.tick > after) return &e;
  return nullptr;
}

// Opens the device and runs the application until the board applies the device's forces.
void openInContact(Session& s) {
  REQUIRE(s.device->open());
  REQUIRE(s.device->getServoLoop() != nullptr);
  REQUIRE(s.board->attached());
  REQUIRE(s.runUntil([&] { return s.boardApplying() && s.linkRunning(); }));
  s.events();  // what happened before the fault is not under test
}

// The board comes back by itself (silent/corrupt for a number of frames) or is replugged: the
// device resumes forces and says so. (A TAU left unpowered rests on its end stops, where its
// kinematics still assemble, so it renders again too.)
void expectRecovery(Session& s, std::vector<ServoEvent>& log, const char* what) {
  const bool link_back = s.runUntil([&] {
    for (const ServoEvent& e : s.events()) log.push_back(e);
    return s.device->getLinkStatus() == LinkStatus::kRunning && first(log, ServoEventKind::kResumed) != nullptr;
  });
  INFO(what);
  REQUIRE(link_back);
  const bool back = s.runUntil([&] { return s.linkRunning() && s.boardApplying(); });
  INFO("last fault: " << uhaptics::toString(s.device->getLastFault()));
  CHECK(back);
  const uhaptics::SessionStatsSnapshot stats = s.device->getSessionStats();
  CHECK(stats.link_losses >= 1);
  CHECK(stats.link_recoveries == stats.link_losses);  // every loss of the link ended
  CHECK(stats.faults >= 1);                            // the ticks without a reading, reported
}

// A fault that starves the host of valid STATEs for `frames` periods.
void starve(const std::string& name, BoardEmulator::Fault fault, const char* what) {
  Session s(name);
  openInContact(s);
  const int frames = 500;  // at least 0.5 s: the application sees the fault whatever its scheduling
  REQUIRE(s.board->inject(fault, frames));
  std::vector<ServoEvent> log;
  bool reported = false, zero_while_reported = true;
  // Until the device reports the fault: kHostWatchdog, kDeviceError; the board then holds zero.
  reported = s.runUntil([&] {
    for (const ServoEvent& e : s.events()) log.push_back(e);
    if (s.device->getLinkStatus() != LinkStatus::kHostWatchdog) return false;
    zero_while_reported = s.boardZero() && s.device->getLastFault() == uhaptics::Fault::kDeviceError;
    return true;
  });
  INFO(name << ", " << what);
  REQUIRE(reported);
  CHECK(zero_while_reported);
  const ServoEvent* missing = first(log, ServoEventKind::kStateMissing);
  const ServoEvent* trip = first(log, ServoEventKind::kHostWatchdog);
  REQUIRE(missing != nullptr);
  REQUIRE(trip != nullptr);
  // Zero from the watchdog_periods-th period without a valid STATE. A loop that stalls that long
  // trips sooner, before its next tick has even missed a STATE (seen under the sanitizers' slowdown).
  if (trip->tick < missing->tick) {
    const ServoEvent* stall = first(log, ServoEventKind::kLoopStalled, trip->tick - 1);
    CHECK((stall != nullptr && stall->tick == trip->tick));  // the stall tripped it, in that period
  }
  const std::uint64_t periods_to_zero = trip->tick >= missing->tick ? trip->tick - missing->tick + 1 : 0;
  CHECK(periods_to_zero <= static_cast<std::uint64_t>(s.watchdog_periods));
  if (fault == BoardEmulator::Fault::kCorrupt) CHECK(first(log, ServoEventKind::kFrameRejected) != nullptr);
  expectRecovery(s, log, what);
  const uhaptics::ServoCounters k = s.device->getServoLoop()->counters();
  CHECK(k.host_watchdog_trips >= 1);
  if (fault == BoardEmulator::Fault::kCorrupt) CHECK(k.frames_rejected >= static_cast<std::uint64_t>(s.watchdog_periods));
  std::cout << name << ", board " << what << " for " << frames << " frames: zero after "
            << periods_to_zero << " periods without a state, link recovered\n";
  CHECK(s.device->close());
}

}  // namespace

TEST_CASE("board faults mid-session: a silent board, for every device", "[chai3d][board][fault]") {
  for (const std::string& name : uhaptics::adapter::deviceNames()) starve(name, BoardEmulator::Fault::kDrop, "silent");
}

TEST_CASE("board faults mid-session: corrupt frames, for every device", "[chai3d][board][fault]") {
  for (const std::string& name : uhaptics::adapter::deviceNames()) starve(name, BoardEmulator::Fault::kCorrupt, "corrupt");
}

TEST_CASE("board faults mid-session: unplugged in contact, then replugged, for every device", "[chai3d][board][fault]") {
  for (const std::string& name : uhaptics::adapter::deviceNames()) {
    INFO(name);
    Session s(name);
    openInContact(s);
    REQUIRE(s.board->unplug());
    CHECK(s.boardZero());  // a bus-powered board loses its power with the cable
    std::vector<ServoEvent> log;
    REQUIRE(s.runUntil([&] {
      for (const ServoEvent& e : s.events()) log.push_back(e);
      return s.device->getLinkStatus() == LinkStatus::kDisconnected;
    }));
    CHECK(s.device->getLastFault() == uhaptics::Fault::kDeviceError);
    CHECK(first(log, ServoEventKind::kDisconnected) != nullptr);
    for (int i = 0; i < 50; ++i) s.appCycle();  // the application carries on against an absent board
    CHECK(s.device->getLinkStatus() == LinkStatus::kDisconnected);
    REQUIRE(s.board->replug());
    expectRecovery(s, log, "replugged");
    CHECK(first(log, ServoEventKind::kReconnected) != nullptr);
    CHECK(s.device->close());
    CHECK(s.device->getLinkStatus() == LinkStatus::kClosed);
    CHECK_FALSE(s.board->attached());  // close() detached the emulator: injecting does nothing
    CHECK_FALSE(s.board->unplug());
  }
}

TEST_CASE("after getServoLoop()->stop() the device reports the link stopped, not the last reading",
          "[chai3d][board][fault]") {
  for (const std::string& name : uhaptics::adapter::deviceNames()) {
    INFO(name);
    Session s(name);
    openInContact(s);
    s.device->getServoLoop()->stop();
    CHECK(s.boardZero());  // stop() commands zero before its thread ends
    for (int i = 0; i < 5; ++i) s.appCycle();
    CHECK(s.device->getLinkStatus() == LinkStatus::kStopped);
    CHECK(s.device->getLastFault() == uhaptics::Fault::kDeviceError);
    CHECK(s.device->getSessionStats().ticks_without_reading > 0);
    CHECK(s.device->close());
  }
}

TEST_CASE("a stalled application: 100 ms without input, the board's efforts ramp to zero in the stated periods, "
          "then the session renders again, for every device", "[chai3d][board][stall]") {
  for (const std::string& name : uhaptics::adapter::deviceNames()) {
    INFO(name);
    Session s(name);
    openInContact(s);
    const std::uint64_t before = s.device->getSessionStats().stale_input_episodes;
    // The application's haptic thread stops calling the device (a breakpoint, a long collision
    // query); this thread only watches the board. Periods are counted in board commands.
    const std::uint64_t stall_start = s.boardState().commands_applied;
    std::uint64_t zero_after = 0;
    const auto t0 = std::chrono::steady_clock::now();
    while (std::chrono::steady_clock::now() - t0 < std::chrono::milliseconds(100)) {
      if (zero_after == 0 && s.boardZero()) zero_after = s.boardState().commands_applied - stall_start;
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
    // Stale after stale_time, then kStaleRampPeriods to zero; one period more for the exchange
    // (the command computed in a period reaches the board in the next) and one for this thread's
    // polling.
    const double periods_stale = s.device->getStaleTime() / s.device->getServoPeriod();
    const auto bound = static_cast<std::uint64_t>(std::ceil(periods_stale)) + cUhapticsDevice::kStaleRampPeriods + 2;
    CHECK(zero_after > 0);
    CHECK(zero_after <= bound);
    CHECK(s.boardZero());
    CHECK(s.device->getSessionStats().stale_input_episodes >= before + 1);
    // Back: the application calls again and the device renders its force.
    REQUIRE(s.runUntil([&] { return s.linkRunning() && s.boardApplying(); }));
    std::cout << name << ", application stalled 100 ms: board at zero after " << zero_after << " periods (bound "
              << bound << "), rendering again\n";
    CHECK(s.device->close());
  }
}

TEST_CASE("soak, short: each device a few seconds under random board faults", "[chai3d][board][soak]") {
  for (const std::string& name : uhaptics::adapter::deviceNames()) {
    uhaptics::soak::Options o;
    o.device = name;
    o.seconds = 4.0;
    o.warmup = 0.5;
    o.mean_fault_interval = 0.2;
    o.seed = 7;
    const uhaptics::soak::Result r = uhaptics::soak::run(o);
    std::cout << uhaptics::soak::summaryCsv({r}, 1 << 16);
    INFO(name << ": " << r.error << "\n" << uhaptics::soak::faultsCsv({r}));
    REQUIRE(r.error.empty());
    CHECK(r.faults.size() >= 3);
    CHECK(r.recovered() == r.faults.size());  // the link comes back after every fault
    CHECK(r.renderingNotResumed() == 0);      // and the device renders again
    CHECK(r.zeroLate() == 0);
    CHECK(r.max_command_ratio <= 1.0);
    CHECK(r.frames_lost + r.frames_rejected + r.host_watchdog_trips + r.disconnects + r.board_resets > 0);  // faults happened
  }
}
