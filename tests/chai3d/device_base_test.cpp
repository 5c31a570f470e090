// cUhapticsDevice around a fixture device: the CHAI3D contract, the clock, the scripted hand, the
// statistics, and the full CHAI3D pipeline (world + stock cToolCursor + mesh) without graphics.
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <limits>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <thread>
#include <vector>

#include "chai3d.h"
#include "point_mass_device.hpp"
#include "uhaptics/tools/alloc_probe.hpp"

using namespace chai3d;

namespace {

uhaptics::DeviceSelection fixtureSelection() {
  uhaptics::DeviceSelection s;
  s.device = "pointmass";
  return s;
}

}  // namespace

TEST_CASE("device contract before and after open", "[chai3d][device]") {
  auto device = std::make_shared<PointMassDevice>(fixtureSelection());
  cGenericHapticDevicePtr generic = device;
  CHECK(device->isDeviceAvailable());
  CHECK_FALSE(device->isDeviceReady());
  CHECK(generic->setForce(cVector3d(1, 0, 0)) == C_ERROR);  // not open: refused
  REQUIRE(generic->open());
  CHECK(generic->calibrate());
  cVector3d p, v;
  cMatrix3d r;
  double gripper = 1.0;
  unsigned int switches = 7;
  CHECK(generic->getPosition(p));
  CHECK(generic->getRotation(r));
  CHECK(generic->getLinearVelocity(v));
  CHECK(generic->getGripperAngleRad(gripper));
  CHECK(generic->getUserSwitches(switches));
  CHECK(gripper == 0.0);
  CHECK(switches == 0u);
  double q[C_MAX_DOF];
  CHECK(generic->getJointAnglesRad(q));
  const cHapticDeviceInfo info = generic->getSpecifications();
  CHECK(info.m_model == C_HAPTIC_DEVICE_CUSTOM);
  CHECK(info.m_manufacturerName == "uhaptics");
  CHECK_THAT(info.m_modelName, Catch::Contains("point mass") && Catch::Contains("sim"));
  CHECK(generic->close());
  CHECK_FALSE(device->isDeviceReady());
}

TEST_CASE("forces flow: in lock-step each command is one servo tick of the device", "[chai3d][device]") {
  auto selection = fixtureSelection();
  selection.hand_enabled = false;
  PointMassDevice device(selection);
  device.setLockStep(true);
  REQUIRE(device.open());
  for (int i = 0; i < 100; ++i) REQUIRE(device.setForce(cVector3d(0.0, 0.0, 1.0)));
  CHECK(device.getSimulationTime() == Approx(0.1));
  // Closed form of m v' = F - b v from rest: v(t) = F/b (1 - exp(-b t / m)); semi-implicit Euler
  // at 1 ms differs from it by O(dt b/m) = 1 % relative.
  cVector3d v;
  device.getLinearVelocity(v);
  const double exact = 1.0 / PointMassDevice::kFriction * (1.0 - std::exp(-PointMassDevice::kFriction * 0.1 / PointMassDevice::kMass));
  CHECK(v.z() == Approx(exact).epsilon(0.02));
  CHECK(device.getForce(v));
  CHECK(v.z() == 1.0);  // getForce() reports the last command, as CHAI3D's devices do
  const auto stats = device.getSessionStats();
  CHECK(stats.ticks == 100);
  CHECK(stats.contacts == 1);
  CHECK(stats.peak_force == 1.0);
}

TEST_CASE("non-finite commands are refused with a fault and a zero command", "[chai3d][device]") {
  auto selection = fixtureSelection();
  selection.hand_enabled = false;
  PointMassDevice device(selection);
  device.setLockStep(true);
  REQUIRE(device.open());
  CHECK(device.setForce(cVector3d(std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0)) == C_ERROR);
  CHECK(device.getLastFault() == uhaptics::Fault::kNonFiniteInput);
  CHECK(device.setForceAndTorque(cVector3d(0, 0, 0), cVector3d(std::numeric_limits<double>::infinity(), 0, 0)) == C_ERROR);
  REQUIRE(device.setForce(cVector3d(0.0, 0.0, 20.0)));  // beyond the fixture's 10 N: saturated
  CHECK(device.plant().actuator.z() == 10.0);
  CHECK(device.getSessionStats().faults == 2);
  CHECK(device.plant().position.allFinite());
}

TEST_CASE("a servo tick through the CHAI3D call allocates nothing", "[chai3d][device]") {
  PointMassDevice device(fixtureSelection());
  device.setLockStep(true);
  REQUIRE(device.open());
  device.setForce(cVector3d(0, 0, 0));
  cVector3d p;
  uhaptics::tools::AllocationScope scope;
  for (int i = 0; i < 500; ++i) {
    device.getPosition(p);
    device.setForce(cVector3d(0.1, 0.0, 0.0));
  }
  CHECK(scope.count() == 0);
}

namespace {

// The application's haptic loop for 200 ms: setForce() as fast as the device lets it.
struct SpinResult {
  std::uint64_t calls = 0;
  double seconds = 0.0;
};
template <class Device>
SpinResult spinApplicationLoop(Device& device) {
  SpinResult r;
  const auto start = std::chrono::steady_clock::now();
  while (std::chrono::steady_clock::now() - start < std::chrono::milliseconds(200)) {
    device.setForce(cVector3d(0, 0, 0));
    ++r.calls;
  }
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return r;
}

}  // namespace

TEST_CASE("real-time mode: servo ticks follow the wall clock, not the call rate", "[chai3d][device]") {
  auto selection = fixtureSelection();
  selection.options["pace"] = 0.0;  // the application's loop spins as fast as it can
  PointMassDevice device(selection);
  REQUIRE_FALSE(device.getPaced());
  REQUIRE(device.open());
  const SpinResult spin = spinApplicationLoop(device);
  const double elapsed = spin.seconds;
  const std::uint64_t calls = spin.calls;
  const auto stats = device.getSessionStats();
  // 1 kHz servo: ticks ~ elapsed / 1 ms. The loop may be descheduled on a loaded 2-core machine, so
  // allow the catch-up cap to drop time: at least half the ticks, never more than the clock allows.
  CHECK(static_cast<double>(stats.ticks) <= elapsed / 1e-3 + 1.0);
  CHECK(static_cast<double>(stats.ticks) >= 0.5 * elapsed / 1e-3);
  CHECK(calls > stats.ticks);  // the application loop spins faster than the servo: commands held
}

TEST_CASE("paced (the default): each force command waits for the next servo period", "[chai3d][device]") {
  PointMassDevice device(fixtureSelection());
  REQUIRE(device.getPaced());
  REQUIRE(device.open());
  const SpinResult spin = spinApplicationLoop(device);
  const double elapsed = spin.seconds;
  const std::uint64_t calls = spin.calls;
  const auto stats = device.getSessionStats();
  // A spinning loop makes thousands of calls per tick; paced, one call per period and one tick per
  // call, give or take the ticks a descheduled loop catches up on (at least half, as above).
  CHECK(static_cast<double>(stats.ticks) <= elapsed / 1e-3 + 1.0);
  CHECK(static_cast<double>(stats.ticks) >= 0.5 * elapsed / 1e-3);
  CHECK(static_cast<double>(calls) <= 1.2 * elapsed / 1e-3 + 2.0);
  CHECK(calls <= stats.ticks + 2);
}

TEST_CASE("the scripted hand moves the device along its path", "[chai3d][hand]") {
  auto selection = fixtureSelection();
  selection.hand.waypoints = {uhaptics::Vec3(0, 0, 0.5), uhaptics::Vec3(0, 0, -0.5)};
  selection.hand.lap_time = 2.0;
  PointMassDevice device(selection);
  device.setLockStep(true);
  REQUIRE(device.open());
  double lowest = 1.0, highest = -1.0;
  cVector3d p;
  for (int i = 0; i < 4000; ++i) {
    device.setForce(cVector3d(0, 0, 0));
    device.getPosition(p);
    if (i > 2000) {  // second lap: past the start-up transient
      lowest = std::min(lowest, p.z());
      highest = std::max(highest, p.z());
    }
  }
  // Path: z from +0.05 m to -0.05 m (0.5 workspace radius of 0.1 m). A spring-damper behind a
  // moving anchor lags and undershoots the turns; within 40 % of the span it went where it was led.
  CHECK(highest > 0.03);
  CHECK(lowest < -0.03);
  CHECK(std::abs(p.x()) < 1e-9);  // the path is vertical: nothing pushes sideways
}

TEST_CASE("a recorded session's hand replays: the device moves as it did", "[chai3d][hand][recording]") {
  auto selection = fixtureSelection();
  selection.hand.waypoints = {uhaptics::Vec3(0, 0, 0.5), uhaptics::Vec3(0.2, 0, -0.5)};
  selection.hand.lap_time = 2.0;
  selection.record_path = "uhaptics-fixture-hand.csv";
  std::remove(selection.record_path.c_str());
  constexpr int kTicks = 3000;
  std::vector<cVector3d> original(kTicks);
  {
    PointMassDevice device(selection);
    device.setLockStep(true);
    REQUIRE(device.open());
    uhaptics::tools::AllocationScope scope;
    for (int i = 0; i < kTicks; ++i) {
      device.setForce(cVector3d(0, 0, 0.5));  // a steady "scene" force the recording keeps
      device.getPosition(original[static_cast<std::size_t>(i)]);
    }
    CHECK(scope.count() == 0);  // recording on: the tick still allocates nothing
    REQUIRE(device.close());
  }
  const uhaptics::HandRecording recorded = uhaptics::readHandRecording(selection.record_path);
  CHECK(recorded.workspace_radius == Approx(0.1));
  CHECK(recorded.device == "pointmass");
  CHECK(recorded.dropped_rows == 0);
  // 100 rows a second over 3 s of ticks (the first at t = 0, the last at 2.99 s).
  REQUIRE(recorded.samples.size() == 300);
  CHECK(recorded.samples[1].time == Approx(0.01));
  CHECK(recorded.samples[150].scene_force.z() == Approx(0.5));
  CHECK(recorded.samples[0].stiffness == Approx(selection.hand.stiffness));
  CHECK(recorded.samples[0].anchor.z() == Approx(0.5));

  // The same device replaying it: the hand pulls the same anchor with the same grip, so the mass
  // follows the same path, apart from the corners the 10 ms rows cut (docs/recording.md).
  auto replay = fixtureSelection();
  replay.hand.recording = std::make_shared<const uhaptics::HandRecording>(recorded);
  PointMassDevice device(replay);
  device.setLockStep(true);
  REQUIRE(device.open());
  double worst = 0.0;
  for (int i = 0; i < kTicks - 10; ++i) {
    cVector3d p;
    device.setForce(cVector3d(0, 0, 0.5));
    device.getPosition(p);
    worst = std::max(worst, (p - original[static_cast<std::size_t>(i)]).length());
  }
  // The anchor moves at 0.1 m/s (1.02 radii a segment, a segment a second): a row period cuts a
  // corner by at most 0.5 mm, which the 150 N/m grip on the 0.2 kg mass smooths further.
  CHECK(worst < 1e-3);
  std::remove(selection.record_path.c_str());
}

TEST_CASE("stats file written on close", "[chai3d][stats]") {
  auto selection = fixtureSelection();
  selection.stats_path = "uhaptics-fixture-stats.json";
  std::remove(selection.stats_path.c_str());
  {
    PointMassDevice device(selection);
    device.setLockStep(true);
    REQUIRE(device.open());
    for (int i = 0; i < 50; ++i) device.setForce(cVector3d(0, 0, 2.0));
    REQUIRE(device.close());
  }
  std::ifstream file(selection.stats_path);
  REQUIRE(file.good());
  std::stringstream text;
  text << file.rdbuf();
  CHECK_THAT(text.str(), Catch::Contains("\"ticks\": 50,") && Catch::Contains("\"peak_force_N\": 2,") &&
                             Catch::Contains("\"renderer\": \"identity\""));
  std::remove(selection.stats_path.c_str());
}

TEST_CASE("stock cToolCursor + mesh: the hand pushes into a box, the proxy pushes back", "[chai3d][pipeline]") {
  // 0.1 m box centred 0.1 m below the workspace centre: its top face at z = -0.05 m. The hand's
  // path goes down to -0.06 m (0.6 of the 0.1 m radius), so contact is certain.
  auto selection = fixtureSelection();
  selection.hand.waypoints = {uhaptics::Vec3(0, 0, 0.3), uhaptics::Vec3(0, 0, -0.6)};
  selection.hand.lap_time = 2.0;
  auto device = std::make_shared<PointMassDevice>(selection);
  device->setLockStep(true);

  cWorld world;
  cMesh* box = new cMesh();
  world.addChild(box);
  cCreateBox(box, 0.1, 0.1, 0.1);
  box->setLocalPos(0.0, 0.0, -0.1);
  box->createAABBCollisionDetector(0.01);  // the tree's margin must cover the tool radius
  box->m_material->setStiffness(1000.0);
  cToolCursor* tool = new cToolCursor(&world);
  world.addChild(tool);
  tool->setHapticDevice(device);
  tool->setRadius(0.005);
  tool->setWorkspaceRadius(0.1);  // world units = device units here
  REQUIRE(tool->start());

  double deepest = 0.0;
  double maxForce = 0.0;
  for (int i = 0; i < 3000; ++i) {
    world.computeGlobalPositions(true);
    tool->updateFromDevice();
    tool->computeInteractionForces();
    tool->applyToDevice();
    const double goal = tool->getHapticPoint(0)->getGlobalPosGoal().z();
    deepest = std::min(deepest, goal - (-0.05 + 0.005));  // penetration of the contact sphere
    maxForce = std::max(maxForce, tool->getDeviceGlobalForce().z());
    CHECK(tool->getDeviceGlobalForce().length() < 1e3);
  }
  const auto stats = device->getSessionStats();
  CHECK(stats.ticks == 3000);
  CHECK(stats.contacts >= 1);
  // At rest in contact the proxy spring (1000 N/m) balances the hand (at most 8 N): < 8 mm deep,
  // and the force CHAI3D sent peaked near the hand's force (above 1 N: a real push, not ripple).
  CHECK(deepest < 0.0);
  CHECK(deepest > -0.012);
  CHECK(maxForce > 1.0);
  CHECK(stats.peak_force == Approx(maxForce).epsilon(1e-9));
  tool->stop();
}
