// Every device the registry offers (exo, tau, rhi, ...) honours CHAI3D's device contract the same
// way and describes itself consistently, on the simulated backend with the scripted hand moving it.
#include <catch2/catch.hpp>
#include <cmath>

#include "chai3d.h"
#include "devices/CMyCustomDevice.h"
#include "uhaptics/chai3d/device_registry.hpp"
#include "uhaptics/chai3d/vector_conversions.hpp"

using namespace chai3d;

TEST_CASE("registry devices: specification complete and consistent", "[chai3d][contract]") {
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

namespace {

// CHAI3D's device contract, asked through a_generic: the device itself, or the one CHAI3D's
// cHapticDeviceHandler hands out (the uhaptics slot, a_throughSlot), whose answers must be the
// device's. a_device: the uhaptics device behind a_generic (the same object when called directly).
void checkContract(const std::string& a_name, const cGenericHapticDevicePtr& a_generic,
                   const cUhapticsDevicePtr& a_device, bool a_throughSlot) {
  const cGenericHapticDevicePtr& generic = a_generic;
  const cUhapticsDevicePtr& device = a_device;
  const std::string& name = a_name;
  device->setLockStep(true);
  CHECK(device->isDeviceAvailable());
  CHECK(generic->isDeviceAvailable());
  CHECK(generic->setForce(cVector3d(0, 0, 0)) == C_ERROR);  // not open: refused
  cVector3d p, v, w;
  CHECK_FALSE(generic->getPosition(p));
  CHECK_FALSE(generic->calibrate());
  CHECK_FALSE(generic->isDeviceReady());
  REQUIRE(generic->open());
  CHECK(generic->isDeviceReady());
  CHECK(device->isDeviceReady());
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
  if (a_throughSlot) {
    // CHAI3D's cMyCustomDevice does not declare getJointAnglesRad: its base class answers C_ERROR.
    // The joint angles are the uhaptics device's to give (uhapticsDevice()).
    REQUIRE(device->getJointAnglesRad(q));
  } else {
    REQUIRE(generic->getJointAnglesRad(q));
  }
  for (int i = 0; i < C_MAX_DOF; ++i) CHECK(std::isfinite(q[i]));
  // The specification, as the device gives it (the slot copies it on open).
  const cHapticDeviceInfo info = generic->getSpecifications(), own = device->getSpecifications();
  CHECK(info.m_model == own.m_model);
  CHECK(info.m_modelName == own.m_modelName);
  CHECK(info.m_maxLinearForce == own.m_maxLinearForce);
  CHECK(info.m_maxLinearStiffness == own.m_maxLinearStiffness);
  CHECK(info.m_maxLinearDamping == own.m_maxLinearDamping);
  CHECK(info.m_workspaceRadius == own.m_workspaceRadius);
  CHECK(info.m_actuatedRotation == own.m_actuatedRotation);

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
  // Every answer the handler's device gives equals the device's own, exactly (the same numbers
  // copied, nothing recomputed). A small force in the device's range: what was accepted is what
  // getForce() reports.
  const cVector3d force(0.0, 0.01, -0.01);
  int answers_differ = 0;
  for (int i = 0; i < ticks; ++i) {
    REQUIRE(generic->setForce(a_throughSlot ? force : cVector3d(0, 0, 0)));
    REQUIRE(generic->getPosition(p));
    REQUIRE(generic->getLinearVelocity(v));
    REQUIRE(generic->getAngularVelocity(w));
    CHECK(toEigen(w).allFinite());
    if (a_throughSlot) {
      cVector3d own_p, own_v, own_w, f, own_f, t;
      cMatrix3d own_r;
      device->getPosition(own_p);
      device->getLinearVelocity(own_v);
      device->getAngularVelocity(own_w);
      generic->getRotation(r);
      device->getRotation(own_r);
      generic->getForce(f);
      device->getForce(own_f);
      generic->getTorque(t);
      const bool same = p.equals(own_p, 0.0) && v.equals(own_v, 0.0) && w.equals(own_w, 0.0) &&
                        f.equals(own_f, 0.0) && f.equals(force, 0.0) && t.equals(cVector3d(0, 0, 0), 0.0) &&
                        r.equals(own_r);
      answers_differ += same ? 0 : 1;
    }
    integral += 0.5 * device->getServoPeriod() * (previous + toEigen(v));
    previous = toEigen(v);
    travelled += (toEigen(p) - last).norm();
    last = toEigen(p);
  }
  CHECK(answers_differ == 0);
  INFO(name << ": travelled " << travelled << " m, displacement " << (last - start).transpose()
            << ", integrated velocity " << integral.transpose());
  CHECK(travelled > 0.05 * device->getSpecifications().m_workspaceRadius);  // the hand moved it
  CHECK((integral - (last - start)).norm() <= 0.05 * travelled + 2e-4);
  CHECK(device->getSessionStats().ticks == static_cast<std::uint64_t>(ticks));
  CHECK(device->getLastFault() == uhaptics::Fault::kNone);

  CHECK(generic->close());
  CHECK_FALSE(generic->isDeviceReady());
  CHECK_FALSE(device->isDeviceReady());
  CHECK(generic->setForce(cVector3d(0, 0, 0)) == C_ERROR);  // closed again
  CHECK(device->getSessionStats().ticks == static_cast<std::uint64_t>(ticks));
  REQUIRE(generic->open());  // and it reopens at the start, counters reset
  CHECK(device->getSessionStats().ticks == 0u);
  CHECK(generic->close());
}

}  // namespace

TEST_CASE("registry devices: the CHAI3D device contract", "[chai3d][contract]") {
  for (const std::string& name : uhaptics::adapter::deviceNames()) {
    DYNAMIC_SECTION(name) {
      uhaptics::DeviceSelection selection;
      selection.device = name;
      selection.hand.lap_time = 2.0;
      const cUhapticsDevicePtr device = uhaptics::adapter::createDevice(selection);
      checkContract(name, device, device, false);
    }
  }
}

TEST_CASE("registry devices: the CHAI3D device contract through CHAI3D's handler (the uhaptics slot)",
          "[chai3d][contract][slot]") {
  for (const std::string& name : uhaptics::adapter::deviceNames()) {
    DYNAMIC_SECTION(name) {
      uhaptics::DeviceSelection selection;
      selection.device = name;
      selection.hand.lap_time = 2.0;
      uhaptics::adapter::selectSlotDevice(selection);
      {
        cHapticDeviceHandler handler;
        REQUIRE(handler.getNumDevices() == 1u);
        cGenericHapticDevicePtr generic;
        REQUIRE(handler.getDevice(generic, 0));
        REQUIRE(std::dynamic_pointer_cast<cMyCustomDevice>(generic) != nullptr);  // the slot, not the stub
        const cUhapticsDevicePtr device = uhaptics::adapter::uhapticsDevice(generic);
        REQUIRE(device != nullptr);
        CHECK(device->getDeviceName() == name);
        checkContract(name, generic, device, true);
      }
      uhaptics::adapter::resetSlotSelection();
    }
  }
}

namespace {
// Passes everything on and counts the commands: what DeviceSelection::wrap_joint_io hands a device.
class CountingJointIo final : public uhaptics::JointIo {
 public:
  explicit CountingJointIo(std::unique_ptr<uhaptics::JointIo> inner)
      : JointIo(inner->spec(), inner->backend()), inner_(std::move(inner)) {}
  void open() override { inner_->open(); }
  void close() noexcept override { inner_->close(); }
  bool isOpen() const noexcept override { return inner_->isOpen(); }
  bool read(double* positions) noexcept override { return inner_->read(positions); }
  std::uint32_t sampleTimeUs() const noexcept override { return inner_->sampleTimeUs(); }
  void command(const double* efforts) noexcept override {
    ++commands;
    inner_->command(efforts);
  }
  uhaptics::Fault advance(double dt) noexcept override { return inner_->advance(dt); }
  bool movesOnlyInAdvance() const noexcept override { return inner_->movesOnlyInAdvance(); }
  bool readUserPoint(uhaptics::Vec3& position, uhaptics::Vec3& velocity) noexcept override {
    return inner_->readUserPoint(position, velocity);
  }
  void setUserForce(const uhaptics::Vec3& force) noexcept override { inner_->setUserForce(force); }
  std::string describe() const override { return inner_->describe() + ", counted"; }
  int commands = 0;

 private:
  std::unique_ptr<uhaptics::JointIo> inner_;
};
}  // namespace

TEST_CASE("registry devices: the selection's wrap_joint_io is the joint I/O the device ticks over",
          "[chai3d][contract]") {
  for (const std::string& name : uhaptics::adapter::deviceNames()) {
    INFO("device " << name);
    CountingJointIo* counting = nullptr;
    uhaptics::DeviceSelection selection;
    selection.device = name;
    selection.hand_enabled = false;
    selection.wrap_joint_io = [&counting](std::unique_ptr<uhaptics::JointIo> io) -> std::unique_ptr<uhaptics::JointIo> {
      auto wrapped = std::make_unique<CountingJointIo>(std::move(io));
      counting = wrapped.get();
      return wrapped;
    };
    chai3d::cUhapticsDevicePtr device = uhaptics::adapter::createDevice(selection);
    device->setLockStep(true);
    REQUIRE(device->open());
    REQUIRE(counting != nullptr);
    const int before = counting->commands;
    for (int i = 0; i < 10; ++i) CHECK(device->setForceAndTorqueAndGripperForce(cVector3d(0, 0, 0.1), cVector3d(0, 0, 0), 0.0));
    CHECK(counting->commands - before == 10);  // one command per lock-step tick, through the wrapper
    CHECK(device->close());

    // A wrapper that returns nothing: open() refuses, nothing runs.
    selection.wrap_joint_io = [](std::unique_ptr<uhaptics::JointIo>) { return std::unique_ptr<uhaptics::JointIo>(); };
    chai3d::cUhapticsDevicePtr refused = uhaptics::adapter::createDevice(selection);
    CHECK_FALSE(refused->open());
    CHECK_FALSE(refused->isDeviceReady());
  }
}
