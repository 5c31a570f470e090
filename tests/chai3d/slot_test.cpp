// CHAI3D's custom-device slot (plugin/chai3d/slot), seen the way an unchanged application sees it:
// through a stock cHapticDeviceHandler. This suite links uhaptics::chai3d, so the handler hands out
// chai3d::cMyCustomDevice as the slot implements it (not CHAI3D's stub).
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <map>
#include <optional>
#include <string>

#include "chai3d.h"
#include "devices/CMyCustomDevice.h"
#include "tool_scene.hpp"
#include "uhaptics/chai3d/CAlgorithmLqrWall.hpp"
#include "uhaptics/chai3d/CExoFingerTool.hpp"
#include "uhaptics/chai3d/CRedundantPlanarDevice.hpp"
#include "uhaptics/chai3d/CTauDevice.hpp"
#include "uhaptics/chai3d/device_registry.hpp"

using namespace chai3d;

namespace {

using Environment = std::map<std::string, std::string>;

// Sets the selection variables for one test and restores them (and the slot's selection) after.
class SelectionEnvironment {
 public:
  explicit SelectionEnvironment(const Environment& a_values) {
    for (const char* name : kNames) {
      const char* value = std::getenv(name);
      if (value != nullptr) m_saved[name] = value;
      ::unsetenv(name);
    }
    for (const auto& [name, value] : a_values) ::setenv(name.c_str(), value.c_str(), 1);
    uhaptics::adapter::resetSlotSelection();
  }
  ~SelectionEnvironment() {
    for (const char* name : kNames) ::unsetenv(name);
    for (const auto& [name, value] : m_saved) ::setenv(name.c_str(), value.c_str(), 1);
    uhaptics::adapter::resetSlotSelection();
  }
  SelectionEnvironment(const SelectionEnvironment&) = delete;
  SelectionEnvironment& operator=(const SelectionEnvironment&) = delete;

 private:
  static constexpr const char* kNames[] = {"UHAPTICS_DEVICE", "UHAPTICS_BACKEND", "UHAPTICS_CONFIG", "UHAPTICS_STATS",
                                           "UHAPTICS_HAND"};
  std::map<std::string, std::string> m_saved;
};

uhaptics::DeviceSelection selection(const std::string& a_device) {
  uhaptics::DeviceSelection s;
  s.device = a_device;
  s.hand.lap_time = 2.0;
  return s;
}

}  // namespace

TEST_CASE("slot: without a usable selection the handler's device is unavailable, with a complete specification",
          "[chai3d][slot]") {
  struct Case {
    const char* label;
    Environment environment;
    const char* reason;  // in the model name
  };
  const Case cases[] = {
      {"nothing selected", {}, "UHAPTICS_DEVICE"},
      {"unknown device", {{"UHAPTICS_DEVICE", "no-such-device"}}, "no-such-device"},
      {"unknown backend", {{"UHAPTICS_DEVICE", "exo"}, {"UHAPTICS_BACKEND", "no-such-backend"}}, "no-such-backend"},
  };
  for (const Case& c : cases) {
    DYNAMIC_SECTION(c.label) {
      SelectionEnvironment environment(c.environment);
      cHapticDeviceHandler handler;
      // One device: the slot's, so the application never gets CHAI3D's null device (whose
      // specification leaves m_model uninitialised: UBSan flags copying it).
      REQUIRE(handler.getNumDevices() == 1u);
      cGenericHapticDevicePtr device;
      REQUIRE(handler.getDevice(device, 0));
      REQUIRE(std::dynamic_pointer_cast<cMyCustomDevice>(device) != nullptr);
      cHapticDeviceInfo info;
      REQUIRE(handler.getDeviceSpecifications(info, 0));  // copies every field: UBSan checks each load
      CHECK(info.m_model == C_HAPTIC_DEVICE_CUSTOM);
      CHECK(info.m_manufacturerName == "uhaptics");
      CHECK_THAT(info.m_modelName, Catch::StartsWith("no device") && Catch::Contains(c.reason));
      CHECK(info.m_workspaceRadius > 0.0);  // CHAI3D's defaults: tools scale by it
      CHECK(info.m_maxLinearStiffness > 0.0);
      CHECK(info.m_maxLinearForce > 0.0);
      CHECK_FALSE(info.m_sensedPosition);
      CHECK_FALSE(info.m_actuatedPosition);
      // Unavailable and refusing everything, with CHAI3D's neutral readings.
      CHECK_FALSE(device->isDeviceAvailable());
      CHECK_FALSE(device->open());
      CHECK_FALSE(device->isDeviceReady());
      CHECK_FALSE(device->calibrate());
      cVector3d p(1, 1, 1), v(1, 1, 1);
      cMatrix3d r;
      r.set(2, 0, 0, 0, 2, 0, 0, 0, 2);
      unsigned int switches = 7;
      double angle = 1.0;
      CHECK_FALSE(device->getPosition(p));
      CHECK(p.equals(cVector3d(0, 0, 0)));
      CHECK_FALSE(device->getRotation(r));
      cMatrix3d identity = cIdentity3d();
      CHECK(r.equals(identity));
      CHECK_FALSE(device->getLinearVelocity(v));
      CHECK(v.equals(cVector3d(0, 0, 0)));
      CHECK_FALSE(device->getUserSwitches(switches));
      CHECK(switches == 0u);
      CHECK_FALSE(device->getGripperAngleRad(angle));
      CHECK(angle == 0.0);
      CHECK(device->setForce(cVector3d(1, 0, 0)) == C_ERROR);
      CHECK_FALSE(device->close());
      CHECK(uhaptics::adapter::uhapticsDevice(device) == nullptr);
      // A stock tool on it starts nothing and stays at rest, as on a missing device.
      ToolScene scene(device, 0.01);
      CHECK_FALSE(scene.tool->start());
      scene.tick();
      CHECK(scene.tool->getDeviceGlobalForce().equals(cVector3d(0, 0, 0)));
    }
  }
}

TEST_CASE("slot: a valid selection from the environment gives that device", "[chai3d][slot]") {
  SelectionEnvironment environment(Environment{{"UHAPTICS_DEVICE", "rhi"}});
  cHapticDeviceHandler handler;
  REQUIRE(handler.getNumDevices() == 1u);
  cGenericHapticDevicePtr device;
  REQUIRE(handler.getDevice(device, 0));
  CHECK(device->isDeviceAvailable());
  CHECK(std::dynamic_pointer_cast<cRedundantPlanarDevice>(uhaptics::adapter::uhapticsDevice(device)) != nullptr);
  CHECK_THAT(device->getSpecifications().m_modelName, Catch::Contains("(uhaptics, sim)"));
}

TEST_CASE("slot: the handler's device reaches the uhaptics device behind it", "[chai3d][slot]") {
  SECTION("devices that are not the slot's") {
    CHECK(uhaptics::adapter::uhapticsDevice(nullptr) == nullptr);
    CHECK(uhaptics::adapter::uhapticsDevice(cGenericHapticDevice::create()) == nullptr);
    const cUhapticsDevicePtr direct = uhaptics::adapter::createDevice(selection("exo"));
    CHECK(uhaptics::adapter::uhapticsDevice(direct) == direct);
  }
  SECTION("one device behind every handler; released with the last") {
    SelectionEnvironment environment(Environment{});
    uhaptics::adapter::selectSlotDevice(selection("exo"));
    std::weak_ptr<cUhapticsDevice> behind;
    {
      auto first = std::make_unique<cHapticDeviceHandler>();
      cHapticDeviceHandler second;
      cGenericHapticDevicePtr a, b;
      REQUIRE(first->getDevice(a, 0));
      REQUIRE(second.getDevice(b, 0));
      CHECK(a != b);  // two cMyCustomDevice objects...
      const cUhapticsDevicePtr device = uhaptics::adapter::uhapticsDevice(a);
      REQUIRE(device != nullptr);
      CHECK(uhaptics::adapter::uhapticsDevice(b) == device);  // ...one uhaptics device
      behind = device;
      // What one is told, the other reports.
      device->setLockStep(true);
      REQUIRE(a->open());
      CHECK(b->isDeviceReady() == false);  // b's members are refreshed by b's own calls
      cVector3d p;
      CHECK(b->getPosition(p));
      CHECK(b->isDeviceReady());
      REQUIRE(a->setForce(cVector3d(0, 0, 0)));
      CHECK(device->getSessionStats().ticks == 1u);
      // The selection cannot change under a live device.
      CHECK_THROWS_AS(uhaptics::adapter::selectSlotDevice(selection("tau")), uhaptics::Error);
      CHECK_THROWS_AS(uhaptics::adapter::resetSlotSelection(), uhaptics::Error);
      // One handler (and its device) gone: the other still has it, open.
      a.reset();
      first.reset();
      CHECK(b->setForce(cVector3d(0, 0, 0)));
      CHECK(device->getSessionStats().ticks == 2u);
    }
    CHECK(behind.expired());  // the last handler gone, nobody holds it: closed and destroyed
  }
}

TEST_CASE("slot: the device-specific functions work on the handler's device", "[chai3d][slot]") {
  SelectionEnvironment environment(Environment{});
  SECTION("exo: cExoFingerTool on the exoskeleton behind the handler's device") {
    uhaptics::adapter::selectSlotDevice(selection("exo"));
    cHapticDeviceHandler handler;
    cGenericHapticDevicePtr generic;
    REQUIRE(handler.getDevice(generic, 0));
    const cExoFingerDevicePtr exo = std::dynamic_pointer_cast<cExoFingerDevice>(uhaptics::adapter::uhapticsDevice(generic));
    REQUIRE(exo != nullptr);
    exo->setLockStep(true);
    cWorld world;
    auto* tool = new cExoFingerTool(&world);
    world.addChild(tool);
    tool->setExoFingerDevice(exo);
    tool->setWorkspaceRadius(exo->getSpecifications().m_workspaceRadius);
    REQUIRE(tool->start());
    for (int i = 0; i < 100; ++i) {
      world.computeGlobalPositions(true);
      tool->updateFromDevice();
      tool->computeInteractionForces();
      tool->applyToDevice();
    }
    CHECK(exo->getSessionStats().ticks == 100u);
    // The handler's device is the same finger: it reads where the tool put it.
    cVector3d p, own;
    REQUIRE(generic->getPosition(p));
    exo->getPosition(own);
    CHECK(p.equals(own));
    CHECK(generic->isDeviceReady());  // the tool opened it; the handler's device says so
    tool->stop();
  }
  SECTION("tau: the wall mode and cAlgorithmLqrWall through the handler's device") {
    // The hand presses down through the block's top face (as in lqr_wall_algorithm_test.cpp).
    uhaptics::DeviceSelection s = selection("tau");
    s.hand.waypoints = {uhaptics::Vec3(0, 0, 0.2), uhaptics::Vec3(0, 0, -0.6)};
    s.hand.stiffness = 1500.0;
    s.hand.damping = 20.0;
    s.hand.max_force = 12.0;
    uhaptics::adapter::selectSlotDevice(s);
    cHapticDeviceHandler handler;
    cGenericHapticDevicePtr generic;
    REQUIRE(handler.getDevice(generic, 0));
    const cTauDevicePtr tau = std::dynamic_pointer_cast<cTauDevice>(uhaptics::adapter::uhapticsDevice(generic));
    REQUIRE(tau != nullptr);
    tau->setLockStep(true);
    tau->setWallMode(cTauDevice::C_TAU_WALL_LQR);
    CHECK(tau->getWallMode() == cTauDevice::C_TAU_WALL_LQR);
    // A stock cursor on the handler's device with the LQR wall in its haptic point.
    ToolScene scene(generic, 0.002);
    scene.addBlock(0.2, generic->getSpecifications().m_maxLinearStiffness);
    cAlgorithmLqrWall* wall = cAlgorithmLqrWall::install(scene.tool->getHapticPoint(0), tau);
    REQUIRE(wall != nullptr);
    REQUIRE(scene.tool->start());
    bool surface = false, engaged = false;
    for (int i = 0; i < 2000; ++i) {  // one lap of the scripted hand (2 s at 1 kHz) presses the block
      scene.tick();
      surface = surface || wall->isSurfaceActive();
      engaged = engaged || tau->isLqrWallEngaged();
    }
    CHECK(surface);  // the algorithm found the block through the handler's device...
    CHECK(engaged);  // ...and the device held it with the LQR wall
    CHECK(tau->getSessionStats().ticks == 2000u);
    CHECK(tau->getSessionStats().faults == 0u);
    scene.tool->stop();
  }
  SECTION("rhi: the null-space options through the handler's device") {
    uhaptics::adapter::selectSlotDevice(selection("rhi"));
    cHapticDeviceHandler handler;
    cGenericHapticDevicePtr generic;
    REQUIRE(handler.getDevice(generic, 0));
    const cRedundantPlanarDevicePtr rhi =
        std::dynamic_pointer_cast<cRedundantPlanarDevice>(uhaptics::adapter::uhapticsDevice(generic));
    REQUIRE(rhi != nullptr);
    auto options = rhi->getNullSpaceOptions();
    options.mu = 3.0;
    REQUIRE(rhi->setNullSpaceOptions(options));
    CHECK(rhi->getNullSpaceOptions().mu == 3.0);
  }
}
