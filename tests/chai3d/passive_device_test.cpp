// The passivity layer in CHAI3D: the device decorator cPassiveHapticDevice around a plain
// cGenericHapticDevice subclass (as CHAI3D's own device classes are) and around a uhaptics device,
// and the servo-path layer switched on by the device option "passivity" in cUhapticsDevice.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "chai3d.h"
#include "point_mass_device.hpp"
#include "uhaptics/backends/board_catalog.hpp"
#include "uhaptics/backends/params_location.hpp"
#include "uhaptics/chai3d/CPassiveHapticDevice.hpp"
#include "uhaptics/chai3d/device_registry.hpp"
#include "uhaptics/tools/alloc_probe.hpp"

using namespace chai3d;

namespace {

constexpr double kT = 1e-3;  // one command = one period of the test device [s]

// A CHAI3D device written as CHAI3D's own device classes are (a cGenericHapticDevice subclass, no
// uhaptics base): a point mass on x with viscous friction, and a handle turning about z with
// rotational friction, each stepped one period per force command (lock-step) with 20 substeps. A
// scripted hand pushes the mass with m_handForce and the handle with m_handTorque. Its velocities are
// the backward differences of its positions (a device's own estimate), or none at all
// (m_reportsVelocity false: CHAI3D's base class then reports zero).
class cLockStepTestDevice : public cGenericHapticDevice {
 public:
  static constexpr double kMass = 0.2, kFriction = 2.0;        // [kg], [N s/m]
  static constexpr double kInertia = 5e-5, kTurnFriction = 5e-4;  // [kg m^2], [N m s/rad]

  cLockStepTestDevice() {
    m_specifications.m_model = C_HAPTIC_DEVICE_VIRTUAL;
    m_specifications.m_modelName = "lock-step test device";
    m_specifications.m_maxLinearForce = 20.0;
    m_specifications.m_maxLinearDamping = 40.0;  // 0.2 m / T
    m_specifications.m_maxAngularDamping = 0.01;  // 0.2 I / T
    m_specifications.m_sensedPosition = true;
    m_specifications.m_sensedRotation = true;
    m_specifications.m_actuatedPosition = true;
    m_specifications.m_actuatedRotation = true;
    m_deviceAvailable = true;
  }
  bool open() override {
    ++m_opens;
    return m_deviceReady = true;
  }
  bool close() override {
    m_deviceReady = false;
    return true;
  }
  bool calibrate(bool a_force) override {
    m_calibratedForce = a_force;
    return m_deviceReady;
  }
  bool getPosition(cVector3d& a_position) override {
    a_position.set(m_x, 0.01, -0.02);
    ++m_positionReads;
    return m_deviceReady;
  }
  bool getLinearVelocity(cVector3d& a_velocity) override {
    if (!m_reportsVelocity) return cGenericHapticDevice::getLinearVelocity(a_velocity);
    a_velocity.set(m_reportedVelocity, 0.0, 0.0);
    return m_deviceReady;
  }
  bool getRotation(cMatrix3d& a_rotation) override {
    a_rotation.identity();
    a_rotation.rotateAboutGlobalAxisRad(cVector3d(0, 0, 1), m_angle);
    return m_deviceReady;
  }
  bool getAngularVelocity(cVector3d& a_velocity) override {
    if (!m_reportsVelocity) return cGenericHapticDevice::getAngularVelocity(a_velocity);
    a_velocity.set(0.0, 0.0, m_reportedTurnRate);
    return m_deviceReady;
  }
  bool getJointAnglesRad(double a_joints[C_MAX_DOF]) override {
    for (int i = 0; i < C_MAX_DOF; ++i) a_joints[i] = 0.1 * i + m_x;
    return m_deviceReady;
  }
  bool getGripperAngleRad(double& a_angle) override {
    a_angle = 0.3;
    return m_deviceReady;
  }
  bool getGripperAngularVelocity(double& a_rate) override {
    a_rate = 0.7;
    return m_deviceReady;
  }
  bool getUserSwitches(unsigned int& a_switches) override {
    a_switches = 5u;
    return m_deviceReady;
  }
  bool enableForces(bool a_value) override {
    m_forcesEnabled = a_value;
    return true;
  }
  bool setForceAndTorqueAndGripperForce(const cVector3d& a_force, const cVector3d& a_torque, double a_gripper) override {
    m_prevForce = a_force;
    m_prevTorque = a_torque;
    m_prevGripperForce = a_gripper;
    constexpr int kSub = 20;
    const double h = kT / kSub, x0 = m_x, a0 = m_angle;
    for (int s = 0; s < kSub; ++s) {  // semi-implicit Euler
      m_v += h * (a_force(0) + m_handForce - kFriction * m_v) / kMass;
      m_x += h * m_v;
      m_w += h * (a_torque(2) + m_handTorque - kTurnFriction * m_w) / kInertia;
      m_angle += h * m_w;
    }
    m_work += a_force(0) * (m_x - x0) + a_torque(2) * (m_angle - a0);
    m_peakWork = std::max(m_peakWork, m_work);
    m_reportedVelocity = (m_x - x0) / kT;
    m_reportedTurnRate = (m_angle - a0) / kT;
    return m_deviceReady;
  }

  double m_x = 0.0, m_v = 0.0, m_angle = 0.0, m_w = 0.0;
  double m_handForce = 0.0, m_handTorque = 0.0;
  bool m_reportsVelocity = true;
  double m_reportedVelocity = 0.0, m_reportedTurnRate = 0.0;
  double m_work = 0.0, m_peakWork = 0.0;  // net true work of the commands on the device [J]
  int m_opens = 0, m_positionReads = 0;
  bool m_calibratedForce = false, m_forcesEnabled = true;
};

// An application's sampled wall (x > 0: F = -K x; angle > 0: tau = -K_r angle) pressed by the hand for
// 2 s and released for 1 s. K T / 2 = 4.5 b in both: beyond Colgate's bound (K above 2 b / T).
constexpr double kWallStiffness = 18000.0;  // [N/m]
constexpr double kTurnStiffness = 4.5;      // [N m/rad]
const double kHandForce = std::sqrt(4.5e-4 * kWallStiffness);  // one wall depth is a quarter mJ
constexpr double kHandTorque = 0.045;

struct WallRun {
  double generated = 0.0, peak_generated = 0.0;  // true work of the commands [J]
  double peak_observed = 0.0;                    // the decorator's observers [J]
  unsigned long long active = 0, faults = 0;
};

WallRun pressWall(bool turn, bool decorated, bool enabled, bool reportsVelocity) {
  auto device = std::make_shared<cLockStepTestDevice>();
  device->m_reportsVelocity = reportsVelocity;
  cGenericHapticDevicePtr used = device;
  cPassiveHapticDevicePtr passive;
  if (decorated) {
    passive = cPassiveHapticDevice::create(device);
    passive->setServoPeriod(kT);
    passive->setPassivityEnabled(enabled);
    used = passive;
  }
  REQUIRE(used->open());
  if (turn) device->m_angle = -kHandTorque / kTurnStiffness;
  else device->m_x = -kHandForce / kWallStiffness;
  for (int k = 0; k < 3000; ++k) {
    const bool pressing = k < 2000;
    if (turn) device->m_handTorque = pressing ? kHandTorque : 0.0;
    else device->m_handForce = pressing ? kHandForce : 0.0;
    cTransform pose;
    used->getTransform(pose);
    const double x = pose.getLocalPos()(0);
    cMatrix3d r = pose.getLocalRot();
    const double angle = std::atan2(r(1, 0), r(0, 0));
    const cVector3d force(!turn && x > 0.0 ? -kWallStiffness * x : 0.0, 0.0, 0.0);
    const cVector3d torque(0.0, 0.0, turn && angle > 0.0 ? -kTurnStiffness * angle : 0.0);
    used->setForceAndTorqueAndGripperForce(force, torque, 0.0);
  }
  WallRun run;
  run.generated = device->m_work;
  run.peak_generated = device->m_peakWork;
  if (passive) {
    run.peak_observed = passive->getPeakEnergyOut();
    run.active = passive->getActiveCount();
    run.faults = passive->getFaultCount();
  }
  return run;
}

uhaptics::DeviceSelection pointMassSelection(double passivity) {
  uhaptics::DeviceSelection s;
  s.device = "pointmass";
  s.hand_enabled = false;
  if (passivity >= 0.0) s.options["passivity"] = passivity;
  return s;
}

}  // namespace

TEST_CASE("passive device: switched off it forwards everything unchanged", "[chai3d][passivity]") {
  auto device = std::make_shared<cLockStepTestDevice>();
  auto passive = cPassiveHapticDevice::create(device);
  passive->setPassivityEnabled(false);
  CHECK(passive->getWrappedDevice() == device);
  CHECK(passive->isDeviceAvailable());
  CHECK_FALSE(passive->isDeviceReady());
  REQUIRE(passive->open());
  CHECK(device->m_opens == 1);
  CHECK(passive->isDeviceReady());
  CHECK(passive->getSpecifications().m_modelName == "lock-step test device");
  CHECK(passive->getSpecifications().m_maxLinearDamping == 40.0);
  CHECK(passive->calibrate(true));
  CHECK(device->m_calibratedForce);

  std::mt19937 rng(1);
  std::uniform_real_distribution<double> uniform(-3.0, 3.0);
  bool identical = true;
  for (int k = 0; k < 2000; ++k) {
    device->m_handForce = uniform(rng);
    cVector3d p, pw, v, vw, w, ww;
    cMatrix3d r, rw;
    passive->getPosition(p);
    device->getPosition(pw);
    passive->getRotation(r);
    device->getRotation(rw);
    passive->getLinearVelocity(v);
    device->getLinearVelocity(vw);
    passive->getAngularVelocity(w);
    device->getAngularVelocity(ww);
    identical = identical && p.equals(pw) && v.equals(vw) && w.equals(ww) && r.equals(rw);
    const cVector3d force(uniform(rng), uniform(rng), uniform(rng)), torque(uniform(rng), 0.0, uniform(rng));
    const double gripper = uniform(rng);
    REQUIRE(passive->setForceAndTorqueAndGripperForce(force, torque, gripper));
    cVector3d sent, sentTorque;
    double sentGripper = 0.0;
    passive->getForce(sent);
    passive->getTorque(sentTorque);
    passive->getGripperForce(sentGripper);
    identical = identical && std::memcmp(&sent, &force, sizeof force) == 0 &&
                std::memcmp(&sentTorque, &torque, sizeof torque) == 0 && sentGripper == gripper;
  }
  CHECK(identical);
  CHECK(passive->getActiveCount() == 0);

  double joints[C_MAX_DOF], wrappedJoints[C_MAX_DOF];
  CHECK(passive->getJointAnglesRad(joints));
  device->getJointAnglesRad(wrappedJoints);
  CHECK(std::memcmp(joints, wrappedJoints, sizeof joints) == 0);
  double value = 0.0;
  CHECK(passive->getGripperAngleRad(value));
  CHECK(value == 0.3);
  CHECK(passive->getGripperAngularVelocity(value));
  CHECK(value == 0.7);
  unsigned int switches = 0;
  CHECK(passive->getUserSwitches(switches));
  CHECK(switches == 5u);
  bool status = false;
  CHECK(passive->getUserSwitch(2, status));
  CHECK(status);
  CHECK(passive->getUserSwitch(1, status));
  CHECK_FALSE(status);
  passive->setEnableGripperUserSwitch(true);
  CHECK(device->getEnableGripperUserSwitch());
  CHECK(passive->getEnableGripperUserSwitch());
  CHECK(passive->enableForces(false));
  CHECK_FALSE(device->m_forcesEnabled);
  CHECK(passive->close());
  CHECK_FALSE(passive->isDeviceReady());
  CHECK_FALSE(device->isDeviceReady());
}

TEST_CASE("passive device: an active sampled wall is made passive, on the force and on the torque",
          "[chai3d][passivity]") {
  REQUIRE(kWallStiffness > 2.0 * cLockStepTestDevice::kFriction / kT);
  REQUIRE(kTurnStiffness > 2.0 * cLockStepTestDevice::kTurnFriction / kT);
  for (const bool turn : {false, true}) {
    INFO((turn ? "torque on the rotation" : "force on the position"));
    const WallRun bare = pressWall(turn, false, false, true);
    const WallRun off = pressWall(turn, true, false, true);
    CHECK(bare.generated > 1e-2);  // the wall alone gives out energy
    CHECK(off.generated == bare.generated);  // the decorator switched off changes nothing
    CHECK(off.peak_observed > 1e-2);         // but observes it
    for (const bool reportsVelocity : {true, false}) {
      INFO("the device reports its velocity: " << reportsVelocity);
      const WallRun on = pressWall(turn, true, true, reportsVelocity);
      INFO("generated " << on.generated << " J, peak " << on.peak_generated << " J, observed " << on.peak_observed);
      CHECK(on.generated <= 1e-3);
      CHECK(on.peak_generated <= 1e-3);
      CHECK(on.peak_observed <= 1e-3);
      CHECK(on.active > 0);
      CHECK(on.faults == 0);
    }
  }
}

TEST_CASE("passive device: non-finite commands or samples send zero and count a fault", "[chai3d][passivity]") {
  auto device = std::make_shared<cLockStepTestDevice>();
  auto passive = cPassiveHapticDevice::create(device);
  passive->setServoPeriod(kT);
  REQUIRE(passive->open());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  CHECK(passive->setForce(cVector3d(1.0, 0.0, 0.0)));
  CHECK(passive->setForce(cVector3d(nan, 0.0, 0.0)) == C_ERROR);
  cVector3d sent;
  device->getForce(sent);
  CHECK(sent.equals(cVector3d(0, 0, 0)));
  CHECK(passive->setForceAndTorque(cVector3d(1, 0, 0), cVector3d(0, 0, std::numeric_limits<double>::infinity())) == C_ERROR);
  device->getForce(sent);
  CHECK(sent.equals(cVector3d(0, 0, 0)));
  device->m_x = nan;  // a broken sensor
  CHECK(passive->setForce(cVector3d(1.0, 0.0, 0.0)) == C_ERROR);
  CHECK(passive->getFaultCount() == 3);
  device->m_x = 0.0;
  device->m_v = 0.0;
  passive->setForce(cVector3d(0.0, 0.0, 0.0));  // the difference velocity still spans the bad sample
  CHECK(passive->setForce(cVector3d(1.0, 0.0, 0.0)));
  CHECK(std::isfinite(passive->getEnergyOut()));
  CHECK_THROWS_AS(passive->setMaxDamping(-1.0, 0.0), uhaptics::Error);
  CHECK_THROWS_AS(passive->setVelocityGuard(0.0, nan), uhaptics::Error);
  CHECK_THROWS_AS(passive->setServoPeriod(-1e-3), uhaptics::Error);
  CHECK_THROWS_AS(cPassiveHapticDevice::create(nullptr), uhaptics::Error);
}

// The decorator as the Z-width harness measures a layer at the tool: the lock-step device (0.2 kg,
// b = 2 N s/m: Colgate and Brown's bound 2 b / T = 4000 N/m at 1 kHz) pressed into an application's
// sampled spring wall of stiffness K by a hand pushing with 8 N (a person's firm push) from rest at
// the surface, held for 2 s, then released. From the device's truth: the net work the commands did
// on it, the spread of its position over the hold's last second (a ring) and the rendered stiffness
// (hand force over the mean penetration there).
struct HoldRun {
  double peak_generated = 0.0;  // [J] the largest net work of the commands on the device so far
  double ring = 0.0;            // [m] max - min position over the hold's last second
  double rendered = 0.0;        // [N/m]
  unsigned long long active = 0;
};

HoldRun holdWall(double stiffness, bool decorated) {
  constexpr double kPush = 8.0;  // [N]
  auto device = std::make_shared<cLockStepTestDevice>();
  cGenericHapticDevicePtr used = device;
  cPassiveHapticDevicePtr passive;
  if (decorated) {
    passive = cPassiveHapticDevice::create(device);
    passive->setServoPeriod(kT);
    used = passive;
  }
  REQUIRE(used->open());
  HoldRun run;
  double lo = std::numeric_limits<double>::infinity(), hi = -lo, sum = 0.0;
  int n = 0;
  for (int k = 0; k < 3000; ++k) {
    device->m_handForce = k < 2000 ? kPush : 0.0;
    cVector3d p;
    used->getPosition(p);
    const double x = p(0);
    if (k >= 1000 && k < 2000) {
      lo = std::min(lo, x);
      hi = std::max(hi, x);
      sum += x;
      ++n;
    }
    used->setForceAndTorqueAndGripperForce(cVector3d(x > 0.0 ? -stiffness * x : 0.0, 0.0, 0.0), cVector3d(0, 0, 0), 0.0);
  }
  run.peak_generated = device->m_peakWork;
  run.ring = hi - lo;
  run.rendered = sum > 0.0 ? kPush / (sum / n) : 0.0;
  if (passive) run.active = passive->getActiveCount();
  return run;
}

TEST_CASE("passive device: measured like the Z-width harness, walls at 2x and 4.5x the device's bound stay put",
          "[chai3d][passivity]") {
  constexpr double kBound = 2.0 * cLockStepTestDevice::kFriction / kT;  // 4000 N/m
  for (const double K : {2.0 * kBound, 4.5 * kBound}) {
    const HoldRun bare = holdWall(K, false), on = holdWall(K, true);
    INFO("K = " << K << " N/m; without the decorator: peak work " << 1e3 * bare.peak_generated << " mJ, ring "
                << 1e3 * bare.ring << " mm; with it: " << 1e3 * on.peak_generated << " mJ, " << 1e3 * on.ring
                << " mm, rendered " << on.rendered << " N/m");
    // Without it the hold is a limit cycle: the tool bounces off the wall by 9.3 and 22 mm, the
    // commands giving 0.66 and 1.8 J.
    CHECK(bare.ring > 5e-3);
    CHECK(bare.peak_generated > 0.1);
    // With it the tool stays within 0.26 and 0.08 mm (the press goes 1 and 0.44 mm deep), the
    // commands give at most 1.3 mJ, and the wall feels as stiff as asked (0.998 K). What is left is
    // the whole-force observer's: the press stores F^2 / (2 K) on its balance (4 and 1.8 mJ), and a
    // ring gives some of it back before the observer sees an excess.
    CHECK(on.ring < 5e-4);
    CHECK(on.peak_generated < 2e-3);
    CHECK(on.rendered == Approx(K).epsilon(0.02));
    CHECK(on.active > 0);
  }
  // Inside the bound the decorator leaves the wall's stiffness alone.
  const HoldRun stable = holdWall(0.5 * kBound, true);
  CHECK(stable.rendered == Approx(0.5 * kBound).epsilon(0.01));
}

TEST_CASE("passive device: a command allocates nothing", "[chai3d][passivity]") {
  auto device = std::make_shared<cLockStepTestDevice>();
  auto passive = cPassiveHapticDevice::create(device);
  REQUIRE(passive->open());
  device->m_handForce = 1.0;
  cVector3d p;
  uhaptics::tools::AllocationScope scope;
  for (int k = 0; k < 1000; ++k) {
    passive->getPosition(p);
    passive->setForce(cVector3d(p(0) > 0.0 ? -2000.0 * p(0) : 0.0, 0.0, 0.0));
  }
  CHECK(scope.count() == 0);
}

TEST_CASE("passive device: around a uhaptics device it forwards the device's state and commands",
          "[chai3d][passivity]") {
  auto device = std::make_shared<PointMassDevice>(pointMassSelection(-1.0));
  device->setLockStep(true);
  auto passive = cPassiveHapticDevice::create(device);
  REQUIRE(passive->open());
  CHECK(passive->getSpecifications().m_maxLinearDamping == 10.0);  // the fixture's specification
  CHECK(passive->getLinearController().options().max_damping == 10.0);
  CHECK(passive->getSpecifications().m_modelName == device->getSpecifications().m_modelName);
  // Switched off: the commands arrive as sent (on, a force that accelerates the mass from rest gives
  // energy out and is damped).
  passive->setPassivityEnabled(false);
  for (int k = 0; k < 100; ++k) REQUIRE(passive->setForce(cVector3d(0.0, 0.0, 1.0)));
  cVector3d p, pw, f;
  passive->getPosition(p);
  device->getPosition(pw);
  CHECK(p.equals(pw));
  CHECK(p(2) > 0.0);
  device->getForce(f);
  CHECK(f.equals(cVector3d(0.0, 0.0, 1.0)));
  CHECK(passive->getEnergyOut() > 0.0);  // observed all the same
  CHECK(passive->close());
  CHECK_FALSE(device->isDeviceReady());
}

TEST_CASE("device option passivity: off by default, on wraps the policy with the device's caps",
          "[chai3d][passivity]") {
  PointMassDevice off(pointMassSelection(-1.0));
  CHECK(off.getPassivityMode() == 0);
  CHECK(off.getRendererName() == "identity");
  off.setLockStep(true);
  REQUIRE(off.open());
  CHECK(off.getPassivityDampingCaps().empty());
  CHECK(off.getSessionStats().figure("passivity_energy_out_mJ") == nullptr);

  PointMassDevice on(pointMassSelection(1.0));
  CHECK(on.getPassivityMode() == 1);
  CHECK(on.getRendererName() == "identity + passivity");
  CHECK(on.getPassivityDampingCaps().empty());  // set up by open()
  on.setLockStep(true);
  REQUIRE(on.open());
  // The mass over 2 T (lock-step sim: no command delay); the fixture's joints are the tool's coordinates.
  const std::vector<double> caps = on.getPassivityDampingCaps();
  REQUIRE(caps.size() == 3);
  for (const double cap : caps) CHECK(cap == Approx(PointMassDevice::kMass / (2.0 * 1e-3)).epsilon(1e-9));
  CHECK(on.getSessionStats().figure("passivity_energy_out_mJ") != nullptr);

  auto selection = pointMassSelection(1.0);
  selection.options["passivity_max_damping"] = 3.0;
  PointMassDevice stated(selection);
  REQUIRE(stated.open());
  CHECK(stated.getPassivityDampingCaps() == std::vector<double>{3.0, 3.0, 3.0});

  selection.options["passivity"] = 3.0;
  CHECK_THROWS_AS(PointMassDevice(selection), uhaptics::Error);
}

TEST_CASE("device option passivity: the servo-path layer takes out what an active application gives",
          "[chai3d][passivity]") {
  // The application renders a negative damper (F = +4 v against the fixture's 2 N s/m friction)
  // after a short push: alone it drives the mass to the effort limit's speed.
  const auto run = [](double passivity, uhaptics::SessionStatsSnapshot& stats) {
    PointMassDevice device(pointMassSelection(passivity));
    device.setLockStep(true);
    REQUIRE(device.open());
    for (int k = 0; k < 2000; ++k) {
      cVector3d v;
      device.getLinearVelocity(v);
      device.setForce(k < 20 ? cVector3d(0.5, 0.0, 0.0) : cVector3d(4.0 * v(0), 0.0, 0.0));
    }
    stats = device.getSessionStats();
    return device.plant().velocity.norm();
  };
  uhaptics::SessionStatsSnapshot bare, passive;
  const double runaway = run(0.0, bare);
  const double held = run(1.0, passive);
  CHECK(runaway > 1.0);
  CHECK(held < 0.05);
  REQUIRE(passive.figure("passivity_peak_excess_mJ") != nullptr);
  CHECK(passive.figure("passivity_peak_excess_mJ")->value <= 1.0);  // [mJ]
  CHECK(passive.figure("passivity_active_ticks")->value > 0.0);
  CHECK(passive.figure("passivity_dissipated_mJ")->value > 0.0);
  CHECK(passive.figure("passivity_faults")->value == 0.0);
  CHECK(passive.faults == 0);

  // A tolerated energy: the layer lets the first 10 J go (0.3 s of it stays far below).
  auto selection = pointMassSelection(1.0);
  selection.options["passivity_energy_threshold"] = 10.0;
  PointMassDevice tolerant(selection);
  CHECK(tolerant.getPassivityEnergyThreshold() == 10.0);
  tolerant.setLockStep(true);
  REQUIRE(tolerant.open());
  for (int k = 0; k < 300; ++k) {
    cVector3d v;
    tolerant.getLinearVelocity(v);
    tolerant.setForce(k < 20 ? cVector3d(0.5, 0.0, 0.0) : cVector3d(4.0 * v(0), 0.0, 0.0));
  }
  const auto tolerated = tolerant.getSessionStats();
  CHECK(tolerated.figure("passivity_active_ticks")->value == 0.0);
  CHECK(tolerated.figure("passivity_peak_excess_mJ")->value > 1.0);
}

TEST_CASE("device option passivity: every registered device runs with the layer on, adding nothing in free space",
          "[chai3d][passivity]") {
  for (const std::string& name : uhaptics::adapter::deviceNames()) {
    INFO("device " << name);
    uhaptics::DeviceSelection selection;
    selection.device = name;
    selection.options["passivity"] = 1.0;
    const cUhapticsDevicePtr device = uhaptics::adapter::createDevice(selection);
    device->setLockStep(true);
    REQUIRE(device->open());
    const std::vector<double> caps = device->getPassivityDampingCaps();
    CHECK(static_cast<int>(caps.size()) >= 1);
    std::string listed;
    for (const double cap : caps) {
      CHECK(std::isfinite(cap));
      CHECK(cap >= 0.0);
      listed += " " + std::to_string(cap);
    }
    // The scripted hand moves the device along its path for 2 s; the application sends no force.
    // The policies' own fields (gravity compensation, null-space control) move the device too; the
    // layer observes the scene's share alone, so it books nothing and never damps.
    for (int k = 0; k < 2000; ++k) REQUIRE(device->setForce(cVector3d(0.0, 0.0, 0.0)));
    const auto stats = device->getSessionStats();
    WARN(name << ": caps" << listed << ", generated " << stats.figure("passivity_generated_mJ")->value
              << " mJ, active ticks " << stats.figure("passivity_active_ticks")->value);
    CHECK(stats.faults == 0);
    CHECK(stats.figure("passivity_faults")->value == 0.0);
    CHECK(stats.figure("passivity_active_ticks")->value == 0.0);
    CHECK(std::abs(stats.figure("passivity_energy_out_mJ")->value) < 1e-6);
    CHECK(device->getRendererName().find(" + passivity") != std::string::npos);
    CHECK(device->close());
  }
}
