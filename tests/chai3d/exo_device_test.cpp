// cExoFingerDevice on the simulated backend with a stock CHAI3D world and cToolCursor (no graphics).
#include <catch2/catch.hpp>
#include <cmath>

#include "chai3d.h"
#include "tool_scene.hpp"
#include "uhaptics/chai3d/CExoFingerDevice.hpp"
#include "uhaptics/core/finite_difference.hpp"
#include "uhaptics/core/passivity_observer.hpp"
#include "uhaptics/tools/alloc_probe.hpp"

using namespace chai3d;

namespace {

uhaptics::DeviceSelection exoSelection(bool lag) {
  uhaptics::DeviceSelection s;
  s.device = "exo";
  s.hand.lap_time = 2.0;  // MCP period; the PIP's is 2/3 of it: the joint motion repeats every 4 s
  s.options["force_loop_lag"] = lag ? 1.0 : 0.0;
  return s;
}

// With a block: a stiff floor under the workspace centre; the fingertip dips into it during flexion.
struct Scene : ToolScene {
  Scene(const cGenericHapticDevicePtr& device, bool with_block) : ToolScene(device, 0.002) {
    if (with_block) addBlock(0.2, device->getSpecifications().m_maxLinearStiffness);
  }
};

}  // namespace

TEST_CASE("exo: specification complete and consistent with the model", "[chai3d][exo]") {
  auto device = cExoFingerDevice::create(exoSelection(true));
  const cHapticDeviceInfo info = device->getSpecifications();
  CHECK(info.m_model == C_HAPTIC_DEVICE_CUSTOM);
  CHECK_THAT(info.m_modelName, Catch::Contains("finger exoskeleton"));
  CHECK(info.m_manufacturerName == "uhaptics");
  // Fingertip force the 50 N actuator can show: the linkage trades force for travel, so it is of
  // the order of the actuator force divided by the fingertip travel per actuator length (> 1).
  CHECK(info.m_maxLinearForce > 1.0);
  CHECK(info.m_maxLinearForce < device->getModel().effortLimits()(0));
  CHECK(info.m_maxLinearStiffness > 50.0);  // Z_x = 1 N m/rad over a finger's ~7 cm lever
  CHECK(info.m_maxLinearStiffness < 2000.0);
  // Workspace: a finger's reach, centimetres.
  CHECK(info.m_workspaceRadius > 0.01);
  CHECK(info.m_workspaceRadius < 0.1);
  CHECK(info.m_sensedPosition);
  CHECK(info.m_actuatedPosition);
  CHECK_FALSE(info.m_sensedRotation);
  CHECK_FALSE(info.m_actuatedRotation);
  CHECK_FALSE(info.m_sensedGripper);
  CHECK(info.m_maxGripperForce == 0.0);
  CHECK(info.m_rightHand);
}

TEST_CASE("exo: the finger moves in the device's y-z plane and joint angles are reported", "[chai3d][exo]") {
  auto device = cExoFingerDevice::create(exoSelection(true));
  device->setLockStep(true);
  REQUIRE(device->open());
  const double r = device->getSpecifications().m_workspaceRadius;
  double y_min = 1, y_max = -1, z_min = 1, z_max = -1;
  cVector3d p;
  for (int i = 0; i < 1000; ++i) {  // one MCP period
    device->setForce(cVector3d(0, 0, 0));
    device->getPosition(p);
    CHECK(p.x() == 0.0);
    y_min = std::min(y_min, p.y()), y_max = std::max(y_max, p.y());
    z_min = std::min(z_min, p.z()), z_max = std::max(z_max, p.z());
  }
  // Flexion-extension sweeps most of the reachable region (the synthesized cycles keep a margin).
  CHECK(z_max - z_min > r);
  CHECK(std::max(std::abs(y_min), std::abs(y_max)) < 1.5 * r);
  double q[C_MAX_DOF];
  REQUIRE(device->getJointAnglesRad(q));
  const auto& model = device->getModel();
  CHECK(q[0] >= model.jointLimits().lower(0) - 1e-9);  // l_x inside the stroke
  CHECK(q[0] <= model.jointLimits().upper(0) + 1e-9);
}

TEST_CASE("exo: free space renders exactly zero force", "[chai3d][exo]") {
  auto device = cExoFingerDevice::create(exoSelection(true));
  device->setLockStep(true);
  Scene scene(device, false);
  REQUIRE(scene.tool->start());
  for (int i = 0; i < 2000; ++i) {
    scene.tick();
    REQUIRE(device->getActuatorForce() == 0.0);
  }
  CHECK(device->getSessionStats().contacts == 0);
}

TEST_CASE("exo: a stock cToolCursor touching a block renders through the subspace proxy, passively",
          "[chai3d][exo]") {
  for (const bool lag : {false, true}) {
    DYNAMIC_SECTION("force loop lag " << lag) {
      auto device = cExoFingerDevice::create(exoSelection(lag));
      device->setLockStep(true);
      Scene scene(device, true);
      REQUIRE(scene.tool->start());
      uhaptics::PassivityObserver<2> port;
      double peak_force = 0.0, stored = 0.0;
      const double zq = device->getModel().effortLimits()(0);  // only for scale below
      (void)zq;
      // The finger's joint motion repeats every 4 s (2000 ticks at 500 Hz): two cycles.
      for (int i = 0; i < 4000; ++i) {
        scene.tick();
        // Work the device does on the finger: finger-joint torque (what the user feels) times the
        // finger's joint motion, exactly as sampled.
        port.update(device->getFingerAngles(), device->getFingerTorque());
        peak_force = std::max(peak_force, std::abs(device->getActuatorForce()));
        // Energy the proxy spring stores at its deepest: |F|^2 / (2 k) with CHAI3D's stiffness.
        const double f = scene.tool->getDeviceGlobalForce().length();
        stored = std::max(stored, f * f / (2.0 * device->getSpecifications().m_maxLinearStiffness));
      }
      const auto stats = device->getSessionStats();
      CHECK(stats.contacts >= 2);   // one dip per cycle at least
      CHECK(peak_force > 1.0);      // newtons at the actuator, not numerical dust
      CHECK(peak_force <= device->getModel().effortLimits()(0));
      CHECK(stats.faults == 0);
      INFO("energy out " << port.energyOut() << " J, peak stored " << stored << " J, peak out " << port.peakEnergyOut());
      // Passive: over whole cycles of a position-driven finger against a static, frictionless
      // block, the device returns no more energy than it took. A sampled-and-held command lags
      // half a period (1 ms) and the board's force loop 5 ms; a spring rendered with a lag tau on a
      // cycle of frequency w returns at most 2 pi w tau of its peak energy per cycle (w = 2 pi/4 s:
      // 0.6 % for the hold, 3 % with the force loop). Allow twice that.
      const double allowed = (lag ? 0.06 : 0.012) * 2.0 * stored;
      CHECK(port.energyOut() <= allowed);
      // The same judged from the plant's truth: the actuator's work on the finger as it applied it
      // (after the force loop), which the device's own view above does not see.
      REQUIRE(stats.has_referee);
      INFO("referee: " << stats.referee.generated_energy_mJ << " mJ given to the finger");
      CHECK(1e-3 * stats.referee.generated_energy_mJ <= allowed);
    }
  }
}

TEST_CASE("exo: renderer figures: proxy solves, contact ticks, proxy distance and actuator force",
          "[chai3d][exo]") {
  for (const bool with_block : {false, true}) {
    DYNAMIC_SECTION((with_block ? "touching a block" : "free space")) {
      auto device = cExoFingerDevice::create(exoSelection(false));
      device->setLockStep(true);
      Scene scene(device, with_block);
      REQUIRE(scene.tool->start());
      const auto& model = device->getModel();
      const auto fingertip = [&](const uhaptics::Vec2& x) {
        uhaptics::ExoFingerPoints points;
        model.points(x, points);
        return points.fingertip;
      };
      const double coupling = 1.0;  // Z_x: the coupling_stiffness option's default [N m/rad]
      std::uint64_t pulled = 0, above = 0, near_threshold = 0;
      double max_distance = 0.0, max_actuator = 0.0;
      for (int i = 0; i < 4000; ++i) {  // two cycles of the finger's joint motion
        const uhaptics::Vec2 x = device->getFingerAngles();  // what this tick starts from
        scene.tick();
        cVector3d sent;
        device->getForce(sent);  // the force this tick rendered (lock-step: one tick per call)
        const uhaptics::Vec2 f(sent.y(), -sent.z());  // the finger plane, hand frame
        max_actuator = std::max(max_actuator, std::abs(device->getActuatorForce()));
        if (f.isZero(0.0)) continue;
        ++pulled;
        // The proxy target the device solves for: the pull read back through Z_x (class comment).
        const uhaptics::Mat2 J = uhaptics::centralDifferenceJacobian(fingertip, x);
        const uhaptics::Vec2 proxy = x + J.transpose() * f / coupling;
        max_distance = std::max(max_distance, 1e3 * (fingertip(proxy) - fingertip(x)).norm());
        above += f.norm() > 0.05 ? 1 : 0;  // the statistics' contact threshold [N]
        near_threshold += std::abs(f.norm() - 0.05) < 0.0005 ? 1 : 0;
      }
      const auto stats = device->getSessionStats();
      REQUIRE(stats.faults == 0);
      const auto* solves = stats.figure("proxy_solves");
      const auto* contact_ticks = stats.figure("proxy_contact_ticks");
      const auto* distance = stats.figure("max_proxy_distance_mm");
      const auto* actuator = stats.figure("max_actuator_force_N");
      REQUIRE(solves != nullptr);
      REQUIRE(contact_ticks != nullptr);
      REQUIRE(distance != nullptr);
      REQUIRE(actuator != nullptr);
      INFO("solves " << solves->value << ", contact ticks " << contact_ticks->value << ", max distance "
                     << distance->value << " mm, max actuator " << actuator->value << " N; ticks with a pull "
                     << pulled << ", above 0.05 N " << above);
      // A solve exactly when the application pulls in the finger plane (free space: none at all).
      CHECK(solves->value == static_cast<double>(pulled));
      // Contact ticks: the pull above 0.05 N. The device measures the pull through J_tip^-T J_tip^T,
      // which is the identity up to rounding and the solve's damping near the straight finger:
      // only pulls within 1 % of the threshold may fall either way.
      CHECK(std::abs(contact_ticks->value - static_cast<double>(above)) <= static_cast<double>(near_threshold));
      // The same model evaluations as the device's: equal to rounding.
      CHECK(distance->value == Approx(max_distance).epsilon(1e-9).margin(1e-12));
      CHECK(actuator->value == max_actuator);  // the command itself, exactly
      if (with_block) {
        CHECK(above > 100);                 // the finger pressed the block for a real part of each cycle
        CHECK(distance->value > 0.1);       // millimetres of proxy travel, not numerical dust
        CHECK(distance->value < 1e3 * 2.0 * device->getSpecifications().m_workspaceRadius);
        CHECK(actuator->value > 1.0);       // newtons at the actuator
        CHECK(actuator->value <= model.effortLimits()(0));
      } else {
        CHECK(pulled == 0);
        CHECK(contact_ticks->value == 0.0);
        CHECK(distance->value == 0.0);
        CHECK(actuator->value == 0.0);
      }
    }
  }
}

TEST_CASE("exo: a servo tick allocates nothing", "[chai3d][exo]") {
  auto device = cExoFingerDevice::create(exoSelection(true));
  device->setLockStep(true);
  Scene scene(device, true);
  REQUIRE(scene.tool->start());
  for (int i = 0; i < 10; ++i) scene.tick();
  uhaptics::tools::AllocationScope scope;
  for (int i = 0; i < 1000; ++i) {
    cVector3d p;
    device->getPosition(p);
    device->setForce(cVector3d(0.0, 0.5, -1.0));
  }
  CHECK(scope.count() == 0);
}
