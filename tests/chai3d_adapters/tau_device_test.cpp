// cTauDevice on the simulated backend with a stock CHAI3D world and cToolCursor (no graphics).
#include <catch2/catch.hpp>
#include <cmath>

#include "chai3d.h"
#include "tool_scene.hpp"
#include "uhaptics/chai3d/CTauDevice.hpp"
#include "uhaptics/tools/alloc_probe.hpp"

using namespace chai3d;

namespace {

constexpr double kToolRadius = 0.001;  // m

// Paper 001's push: a hand that presses 8-15 N into the wall. Here a stiff hand spring (1500 N/m)
// led 10 mm below the surface, saturating at 12 N.
uhaptics::DeviceSelection tauSelection(cTauDevice::cWallMode mode) {
  uhaptics::DeviceSelection s;
  s.device = "tau";
  s.hand.waypoints = {uhaptics::Vec3(0, 0, 0.2), uhaptics::Vec3(0, 0, -0.6)};
  s.hand.lap_time = 2.0;
  s.hand.stiffness = 1500.0;
  s.hand.damping = 20.0;
  s.hand.max_force = 12.0;
  s.options["wall"] = mode;
  return s;
}

struct Result {
  double max_penetration = 0.0;  // m, tool centre below (surface + tool radius)
  bool lqr_engaged = false;
  std::uint64_t contacts = 0;
};

// A rigid block (a mesh, CHAI3D's finger proxy) whose top face is 0.2 workspace radii below the
// centre; the hand pushes the tool into it for two laps.
Result pushIntoBlock(cTauDevice::cWallMode mode, double stiffness) {
  auto device = cTauDevice::create(tauSelection(mode));
  device->setLockStep(true);
  const double r = device->getSpecifications().m_workspaceRadius;
  ToolScene scene(device, kToolRadius);
  scene.addBlock(0.2, stiffness);
  cToolCursor* tool = scene.tool;
  REQUIRE(tool->start());
  const double surface = -0.2 * r + kToolRadius;
  Result result;
  for (int i = 0; i < 4000; ++i) {
    scene.tick();
    result.max_penetration = std::max(result.max_penetration, surface - tool->getDeviceGlobalPos().z());
    result.lqr_engaged = result.lqr_engaged || device->isLqrWallEngaged();
    REQUIRE(device->getLastFault() == uhaptics::Fault::kNone);
  }
  result.contacts = device->getSessionStats().contacts;
  return result;
}

}  // namespace

TEST_CASE("tau: specification complete and consistent with the model", "[chai3d_adapters][tau]") {
  auto device = cTauDevice::create(tauSelection(cTauDevice::C_TAU_WALL_AUTO));
  const cHapticDeviceInfo info = device->getSpecifications();
  CHECK(info.m_model == C_HAPTIC_DEVICE_CUSTOM);
  CHECK_THAT(info.m_modelName, Catch::Contains("TAU"));
  CHECK(info.m_manufacturerName == "uhaptics");
  CHECK(info.m_maxLinearForce > 1.0);  // newtons from 2 N m joints on centimetre levers
  CHECK(info.m_maxAngularTorque > 0.0);
  CHECK(info.m_maxLinearStiffness == 6000.0);
  CHECK(info.m_workspaceRadius == Approx(0.025));  // paper 001: a 50 mm cube
  CHECK(info.m_sensedPosition);
  CHECK(info.m_sensedRotation);
  CHECK(info.m_actuatedPosition);
  CHECK(info.m_actuatedRotation);
  CHECK(info.m_maxGripperForce == 0.0);
  REQUIRE(device->open());
  cVector3d p;
  cMatrix3d R;
  device->getPosition(p);
  device->getRotation(R);
  CHECK(p.length() < 1e-3);  // starts at the workspace centre
  CHECK(cAbs(R.getCol0().dot(cVector3d(1, 0, 0)) - 1.0) < 1e-3);
  double q[C_MAX_DOF];
  CHECK(device->getJointAnglesRad(q));
}

TEST_CASE("tau: free space holds gravity, forces flow through J^T", "[chai3d_adapters][tau]") {
  auto selection = tauSelection(cTauDevice::C_TAU_WALL_SPRING);
  selection.hand_enabled = false;
  auto device = cTauDevice::create(selection);
  device->setLockStep(true);
  REQUIRE(device->open());
  cVector3d p;
  for (int i = 0; i < 500; ++i) device->setForce(cVector3d(0, 0, 0));
  device->getPosition(p);
  CHECK(p.length() < 1e-3);  // gravity compensated: no sag beyond a millimetre in 0.5 s
  // 1 N up for 30 ms, nothing holding it: it rises (a few millimetres, well inside the workspace).
  // The task-space inertia is not isotropic, so the velocity need not be exactly along the force;
  // it must be mostly upward.
  for (int i = 0; i < 30; ++i) device->setForce(cVector3d(0, 0, 1.0));
  cVector3d v;
  device->getLinearVelocity(v);
  INFO("velocity " << v.str(4));
  CHECK(v.z() > 0.01);
  CHECK(v.z() > 2.0 * std::max(std::abs(v.x()), std::abs(v.y())));
}

TEST_CASE("tau: the LQR wall holds a 12 N push against a rigid mesh under 1 mm, the spring does not",
          "[chai3d_adapters][tau]") {
  const Result lqr = pushIntoBlock(cTauDevice::C_TAU_WALL_AUTO, 6000.0);
  CHECK(lqr.lqr_engaged);
  CHECK(lqr.contacts >= 1);
  CHECK(lqr.max_penetration > 0.0);
  CHECK(lqr.max_penetration < 1e-3);  // paper 001: maximum penetration below 1 mm
  // The same push on the spring baseline sinks F / k = 12 / 6000 = 2 mm: the bound discriminates.
  const Result spring = pushIntoBlock(cTauDevice::C_TAU_WALL_SPRING, 6000.0);
  CHECK_FALSE(spring.lqr_engaged);
  CHECK(spring.max_penetration > 1.5e-3);
}

TEST_CASE("tau: a soft object stays with the spring (no LQR wall)", "[chai3d_adapters][tau]") {
  const Result soft = pushIntoBlock(cTauDevice::C_TAU_WALL_AUTO, 500.0);  // below the 3000 N/m threshold
  CHECK(soft.contacts >= 1);
  CHECK_FALSE(soft.lqr_engaged);
}

TEST_CASE("tau: a servo tick allocates nothing", "[chai3d_adapters][tau]") {
  auto device = cTauDevice::create(tauSelection(cTauDevice::C_TAU_WALL_LQR));
  device->setLockStep(true);
  REQUIRE(device->open());
  cVector3d p;
  for (int i = 0; i < 10; ++i) device->setForce(cVector3d(0, 0, 1.0));
  uhaptics::tools::AllocationScope scope;
  for (int i = 0; i < 1000; ++i) {
    device->getPosition(p);
    device->setForce(cVector3d(0.0, 0.0, i % 200 < 100 ? 5.0 : 0.0));  // in and out of contact
  }
  CHECK(scope.count() == 0);
}
