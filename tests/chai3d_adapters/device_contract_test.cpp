// Every device the registry offers (exo, tau, rhi, ...) honours CHAI3D's device contract the same
// way and describes itself consistently, on the simulated backend with the scripted hand moving it.
#include <catch2/catch.hpp>
#include <cmath>

#include "chai3d.h"
#include "uhaptics/chai3d/device_registry.hpp"

using namespace chai3d;

namespace {

uhaptics::Vec3 toEigen(const cVector3d& v) { return uhaptics::Vec3(v.x(), v.y(), v.z()); }

}  // namespace

TEST_CASE("registry devices: specification complete and consistent", "[chai3d_adapters][contract]") {
  for (const std::string& name : uhaptics::adapter::deviceNames()) {
    DYNAMIC_SECTION(name) {
      uhaptics::DeviceSelection selection;
      selection.device = name;
      const cUhapticsDevicePtr device = uhaptics::adapter::createDevice(selection);
      const cHapticDeviceInfo info = device->getSpecifications();
      CHECK(info.m_model == C_HAPTIC_DEVICE_CUSTOM);
      CHECK(info.m_manufacturerName == "uhaptics");
      CHECK_THAT(info.m_modelName, Catch::Contains("(uhaptics, sim)"));
      CHECK(device->getDeviceName() == name);
      CHECK_FALSE(device->getRendererName().empty());
      // Every uhaptics device renders a force in a workspace of centimetres to decimetres.
      CHECK(info.m_maxLinearForce > 0.1);
      CHECK(info.m_maxLinearStiffness > 0.0);
      CHECK(info.m_maxLinearDamping >= 0.0);
      CHECK(info.m_workspaceRadius > 0.005);
      CHECK(info.m_workspaceRadius < 0.5);
      CHECK(info.m_sensedPosition);
      CHECK(info.m_actuatedPosition);
      // Angular limits exist exactly when the orientation is actuated; nothing has a gripper.
      CHECK(info.m_actuatedRotation == (info.m_maxAngularTorque > 0.0));
      CHECK(info.m_actuatedRotation == (info.m_maxAngularStiffness > 0.0));
      CHECK((info.m_maxAngularDamping > 0.0) <= info.m_actuatedRotation);
      CHECK((info.m_actuatedRotation <= info.m_sensedRotation));
      CHECK_FALSE(info.m_sensedGripper);
      CHECK_FALSE(info.m_actuatedGripper);
      CHECK(info.m_maxGripperForce == 0.0);
      CHECK((info.m_rightHand || info.m_leftHand));
    }
  }
}

TEST_CASE("registry devices: the CHAI3D device contract", "[chai3d_adapters][contract]") {
  for (const std::string& name : uhaptics::adapter::deviceNames()) {
    DYNAMIC_SECTION(name) {
      uhaptics::DeviceSelection selection;
      selection.device = name;
      selection.hand.lap_time = 2.0;
      const cUhapticsDevicePtr device = uhaptics::adapter::createDevice(selection);
      cGenericHapticDevicePtr generic = device;
      device->setLockStep(true);
      CHECK(device->isDeviceAvailable());
      CHECK(generic->setForce(cVector3d(0, 0, 0)) == C_ERROR);  // not open: refused
      cVector3d p, v, w;
      CHECK_FALSE(generic->getPosition(p));
      CHECK_FALSE(generic->calibrate());
      REQUIRE(generic->open());
      CHECK(generic->calibrate());
      CHECK(generic->calibrate(true));
      cMatrix3d r;
      double gripper = 1.0, gripper_velocity = 1.0;
      unsigned int switches = 7;
      bool pressed = true;
      REQUIRE(generic->getPosition(p));
      CHECK(toEigen(p).allFinite());
      CHECK(generic->getRotation(r));
      CHECK(std::abs(r.det() - 1.0) < 1e-9);  // a rotation
      CHECK(generic->getGripperAngleRad(gripper));
      CHECK(generic->getGripperAngularVelocity(gripper_velocity));
      CHECK(generic->getUserSwitches(switches));
      CHECK(generic->getUserSwitch(0, pressed));
      CHECK(gripper == 0.0);
      CHECK(gripper_velocity == 0.0);
      CHECK(switches == 0u);
      CHECK_FALSE(pressed);
      double q[C_MAX_DOF];
      REQUIRE(generic->getJointAnglesRad(q));
      for (int i = 0; i < C_MAX_DOF; ++i) CHECK(std::isfinite(q[i]));

      // The reported velocity is the motion's: integrated over 0.5 s of the hand moving the device
      // (trapezoidal rule) it matches the displacement. Error budget: the trapezoidal rule on a
      // velocity sampled at 0.5-2 ms, plus TAU's encoder quantization (0.05 mm) at both ends: 5 %
      // of the distance travelled plus 0.2 mm.
      const int ticks = static_cast<int>(0.5 / device->getServoPeriod());
      generic->getPosition(p);
      generic->getLinearVelocity(v);
      const uhaptics::Vec3 start = toEigen(p);
      uhaptics::Vec3 integral = uhaptics::Vec3::Zero(), previous = toEigen(v), last = start;
      double travelled = 0.0;
      for (int i = 0; i < ticks; ++i) {
        REQUIRE(generic->setForce(cVector3d(0, 0, 0)));
        REQUIRE(generic->getPosition(p));
        REQUIRE(generic->getLinearVelocity(v));
        REQUIRE(generic->getAngularVelocity(w));
        CHECK(toEigen(w).allFinite());
        integral += 0.5 * device->getServoPeriod() * (previous + toEigen(v));
        previous = toEigen(v);
        travelled += (toEigen(p) - last).norm();
        last = toEigen(p);
      }
      INFO(name << ": travelled " << travelled << " m, displacement " << (last - start).transpose()
                << ", integrated velocity " << integral.transpose());
      CHECK(travelled > 0.05 * device->getSpecifications().m_workspaceRadius);  // the hand moved it
      CHECK((integral - (last - start)).norm() <= 0.05 * travelled + 2e-4);
      CHECK(device->getSessionStats().ticks == static_cast<std::uint64_t>(ticks));
      CHECK(device->getLastFault() == uhaptics::Fault::kNone);

      CHECK(generic->close());
      CHECK(generic->setForce(cVector3d(0, 0, 0)) == C_ERROR);  // closed again
      CHECK(device->getSessionStats().ticks == static_cast<std::uint64_t>(ticks));
      REQUIRE(generic->open());  // and it reopens at the start, counters reset
      CHECK(device->getSessionStats().ticks == 0u);
      CHECK(generic->close());
    }
  }
}
