// cExoFingerTool (multi-point finger) on cExoFingerDevice's simulated backend, no graphics.
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <thread>

#include "chai3d.h"
#include "uhaptics/chai3d/CExoFingerTool.hpp"
#include "uhaptics/chai3d/vector_conversions.hpp"
#include "uhaptics/core/finite_difference.hpp"
#include "uhaptics/core/passivity_observer.hpp"
#include "uhaptics/tools/alloc_probe.hpp"

using namespace chai3d;

namespace {

constexpr double kPointRadius = 0.001;  // m

uhaptics::DeviceSelection fingerToolSelection(bool hand) {
  uhaptics::DeviceSelection s;
  s.device = "exo";
  s.hand_enabled = hand;  // off: the finger rests at mid-range
  s.hand.lap_time = 2.0;  // MCP period; the joint motion repeats every 4 s
  s.options["force_loop_lag"] = 0.0;
  return s;
}

struct FingerScene {
  cWorld world;
  cExoFingerTool* tool = nullptr;
  double stiffness = 0.0;
  explicit FingerScene(const cExoFingerDevicePtr& device) {
    tool = new cExoFingerTool(&world);
    world.addChild(tool);
    tool->setExoFingerDevice(device);
    tool->setRadius(kPointRadius);
    tool->setWorkspaceRadius(device->getSpecifications().m_workspaceRadius);  // world = device frame
    stiffness = device->getSpecifications().m_maxLinearStiffness;
  }
  // brute_force: see lqr_wall_algorithm_test.cpp (CHAI3D's AABB queries allocate).
  cMesh* addBox(const cVector3d& centre, const cMatrix3d& rotation, double sx, double sy, double sz,
                bool brute_force = false) {
    cMesh* box = new cMesh();
    world.addChild(box);
    cCreateBox(box, sx, sy, sz);
    box->setLocalPos(centre);
    box->setLocalRot(rotation);
    if (brute_force) box->createBruteForceCollisionDetector();
    else box->createAABBCollisionDetector(kPointRadius);
    box->m_material->setStiffness(stiffness);
    return box;
  }

  // A stiff block under the workspace centre (r: the device's workspace radius): during flexion the
  // middle phalanx and the fingertip dip into it.
  cMesh* addBlockUnderCentre(double r, bool brute_force = false) {
    return addBox(cVector3d(0, 0, -1.2 * r), cIdentity3d(), 4 * r, 4 * r, 2 * r, brute_force);
  }
  void tick() {
    world.computeGlobalPositions(true);
    tool->updateFromDevice();
    tool->computeInteractionForces();
    tool->applyToDevice();
  }
};

// A block beside one phalanx (on its dorsal side, away from the other phalanx) of the resting
// finger, 2 mm away; its face half the phalanx long, centred on it: it covers the points at 1/3 and
// 2/3, not the joints. Returns the phalanx's dorsal normal: the way to move the hand into the block.
uhaptics::Vec3 addBoxBesidePhalanx(FingerScene& a_scene, const cExoFingerDevicePtr& a_device,
                                   cExoFingerTool::cPhalanx a_phalanx) {
  const uhaptics::Vec2 x = 0.5 * (a_device->getModel().taskLower() + a_device->getModel().taskUpper());
  const cExoFingerTool::cPhalanxPoint from{a_phalanx, 0.0}, to{a_phalanx, 1.0}, mid{a_phalanx, 0.5};
  const uhaptics::Vec3 along = (a_scene.tool->position(to, x) - a_scene.tool->position(from, x)).normalized();
  // Dorsal normal: opposite to the way flexion of the phalanx's own joint moves it. The other
  // phalanx lies on its palmar side (the finger is flexed), so it cannot reach the block.
  const uhaptics::Vec3 out = -a_scene.tool->jacobian(mid, x).col(a_phalanx).normalized();
  const double length = (a_scene.tool->position(to, x) - a_scene.tool->position(from, x)).norm();
  const double gap = 0.002, thickness = 0.01;
  cMatrix3d R;
  R.setCol0(cVector3d(1, 0, 0));
  R.setCol1(toChai(along));
  R.setCol2(toChai(out));
  a_scene.addBox(toChai(a_scene.tool->position(mid, x) + (gap + kPointRadius + 0.5 * thickness) * out), R, 0.03,
                 0.5 * length, thickness);
  return out;
}

// A steady contact on a resting finger: the box beside the proximal phalanx, the hand (the tool
// frame) moved 5 mm towards it (2 mm gap), then held, as in "a box pressed on one phalanx" below.
void pressProximalPhalanx(FingerScene& a_scene, const cExoFingerDevicePtr& a_device) {
  const uhaptics::Vec3 out = addBoxBesidePhalanx(a_scene, a_device, cExoFingerTool::C_PHALANX_PROXIMAL);
  REQUIRE(a_scene.tool->start());
  const int steps = 250;
  for (int i = 0; i <= steps + 50; ++i) {
    a_scene.tool->setLocalPos(toChai(std::min(i, steps) * (0.005 / steps) * out));
    a_scene.tick();
  }
}

double secondsSince(std::chrono::steady_clock::time_point a_start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - a_start).count();
}

}  // namespace

TEST_CASE("exo finger tool: phalanx Jacobians match finite differences of the points",
          "[chai3d][exo_tool]") {
  auto device = cExoFingerDevice::create(fingerToolSelection(false));
  FingerScene scene(device);
  const uhaptics::Vec2 x(0.7, 0.9);
  for (const auto& point : cExoFingerTool::defaultPoints()) {
    const auto fd = uhaptics::centralDifferenceJacobian([&](const uhaptics::Vec2& y) { return scene.tool->position(point, y); }, x);
    // Central differences of sines and cosines on ~5 cm levers: truncation ~1e-9 m/rad.
    CHECK((scene.tool->jacobian(point, x) - fd).norm() < 1e-7);
    CHECK(scene.tool->jacobian(point, x).row(0).isZero(0.0));  // nothing out of the finger's plane
  }
  CHECK_THROWS_AS(cExoFingerTool(&scene.world, {{cExoFingerTool::C_PHALANX_MIDDLE, 1.5}}), uhaptics::Error);
  CHECK_THROWS_AS(cExoFingerTool(&scene.world, {}), uhaptics::Error);
}

// A block beside one phalanx (on its dorsal side, away from the other phalanx); the hand (the tool
// frame) moves the resting finger into it. Only that phalanx's points may feel a force.
TEST_CASE("exo finger tool: a box pressed on one phalanx loads only that phalanx",
          "[chai3d][exo_tool]") {
  for (const auto phalanx : {cExoFingerTool::C_PHALANX_PROXIMAL, cExoFingerTool::C_PHALANX_MIDDLE}) {
    DYNAMIC_SECTION("phalanx " << phalanx) {
      auto device = cExoFingerDevice::create(fingerToolSelection(false));
      device->setLockStep(true);
      FingerScene scene(device);
      const uhaptics::Vec2 x = 0.5 * (device->getModel().taskLower() + device->getModel().taskUpper());
      const uhaptics::Vec3 out = addBoxBesidePhalanx(scene, device, phalanx);
      REQUIRE(scene.tool->start());
      for (int i = 0; i < 10; ++i) scene.tick();
      REQUIRE(scene.tool->getFingerAngles().isApprox(x, 1e-9));
      // Move the hand 5 mm along the outward normal over 0.5 s (the box is 2 mm away), then hold.
      const int steps = 250;
      for (int i = 0; i <= steps + 50; ++i) {
        scene.tool->setLocalPos(toChai(std::min(i, steps) * (0.005 / steps) * out));
        scene.tick();
      }
      const double depth = 0.003;  // 5 mm travel - 2 mm gap
      uhaptics::Vec2 expected = uhaptics::Vec2::Zero();
      int touching = 0;
      for (int i = 0; i < 6; ++i) {
        const auto& point = scene.tool->getPhalanxPoint(i);
        const cVector3d f = scene.tool->getPointGlobalForce(i);
        INFO("point " << i << " phalanx " << point.m_phalanx << " fraction " << point.m_fraction << " force "
                      << f.str(4));
        const bool on_face = point.m_phalanx == phalanx && point.m_fraction > 0.2 && point.m_fraction < 0.8;
        if (!on_face) {
          CHECK(f.length() == 0.0);  // exactly: its proxy never met a surface
          continue;
        }
        ++touching;
        // The block pushes back along -out with CHAI3D's proxy spring: k * depth.
        CHECK(f.length() == Approx(scene.stiffness * depth).epsilon(0.05));
        CHECK(toEigen(f).normalized().dot(-out) > 0.999);
        expected += scene.tool->jacobian(point, x).transpose() * toEigen(f);
      }
      CHECK(touching == 2);
      const uhaptics::Vec2 tau = scene.tool->getFingerJointTorque();
      INFO("joint torque " << tau.transpose());
      CHECK((tau - expected).norm() <= 1e-12 * expected.norm());
      if (phalanx == cExoFingerTool::C_PHALANX_PROXIMAL) {
        CHECK(tau(1) == 0.0);  // the proximal phalanx cannot load the PIP joint
        CHECK(std::abs(tau(0)) > 1e-3);
      } else {
        CHECK(std::abs(tau(1)) > 1e-3);
      }
      // The device rendered it through the subspace proxy: a nonzero, bounded actuator force.
      CHECK(std::abs(device->getActuatorForce()) > 0.01);
      CHECK(std::abs(device->getActuatorForce()) <= device->getModel().effortLimits()(0));
      CHECK(device->getLastFault() == uhaptics::Fault::kNone);
    }
  }
}

TEST_CASE("exo finger tool: pressing into a block and releasing is passive", "[chai3d][exo_tool]") {
  auto device = cExoFingerDevice::create(fingerToolSelection(true));
  device->setLockStep(true);
  FingerScene scene(device);
  scene.addBlockUnderCentre(device->getSpecifications().m_workspaceRadius);
  REQUIRE(scene.tool->start());
  uhaptics::PassivityObserver<2> port;
  double stored = 0.0, peak_torque = 0.0;
  int contact_frames = 0;
  for (int i = 0; i < 4000; ++i) {  // two full cycles of the finger's joint motion
    scene.tick();
    port.update(device->getFingerAngles(), device->getFingerTorque());
    double energy = 0.0;  // what the points' proxy springs hold now: sum |F_i|^2 / (2 k)
    for (int p = 0; p < 6; ++p) energy += scene.tool->getPointGlobalForce(p).lengthsq() / (2.0 * scene.stiffness);
    stored = std::max(stored, energy);
    peak_torque = std::max(peak_torque, scene.tool->getFingerJointTorque().norm());
    contact_frames += scene.tool->getFingerJointTorque().isZero(0.0) ? 0 : 1;
  }
  INFO("energy out " << port.energyOut() << " J, peak stored " << stored << " J, contact frames " << contact_frames);
  if (std::getenv("UHAPTICS_TEST_REPORT") != nullptr) WARN("energy out " << port.energyOut() << " J, peak stored " << stored << " J, contact frames " << contact_frames);
  CHECK(contact_frames > 200);  // the finger spent a real part of the cycle in the block
  CHECK(peak_torque > 1e-3);
  CHECK(device->getSessionStats().faults == 0);
  // Passive over whole cycles (as for the stock cursor, exo_device_test): a command held over one
  // 2 ms period lags 1 ms, and a spring rendered with lag tau on a cycle of frequency w returns at
  // most 2 pi w tau of its peak energy per cycle (0.6 % at w = 2 pi / 4 s); allow twice that.
  CHECK(port.energyOut() <= 0.012 * 2.0 * stored);
}

// CHAI3D's force rise (cGenericTool::applyToDevice): from engagement the command is scaled by
// t / rise time, t on CHAI3D's wall clock, until the rise time has passed. The bounds below hold
// whatever the machine's speed: the rise clock starts after t0 and is read before each frame ends.
TEST_CASE("exo finger tool: CHAI3D's force rise ramps the joint torque up after engagement",
          "[chai3d][exo_tool]") {
  auto device = cExoFingerDevice::create(fingerToolSelection(false));
  device->setLockStep(true);
  FingerScene scene(device);
  pressProximalPhalanx(scene, device);
  const uhaptics::Vec2 full = scene.tool->getFingerJointTorque();
  REQUIRE(full.norm() > 1e-3);
  // CHAI3D's default (no rise): engaged, the device holds the tool's torque as computed.
  CHECK(device->getFingerJointTorque() == full);
  scene.tool->setForcesOFF();
  CHECK(device->getFingerJointTorque().isZero(0.0));

  SECTION("during the rise, the torque times the elapsed share of the rise time") {
    const double rise = 1000.0;  // s: far longer than the frames below, so the ramp is under way throughout
    scene.tool->setUseForceRise(true);
    scene.tool->setRiseTime(rise);
    const auto t0 = std::chrono::steady_clock::now();
    REQUIRE(scene.tool->setForcesON());
    double previous = 0.0;
    for (int i = 0; i < 200; ++i) {
      scene.tick();
      const double elapsed = secondsSince(t0);
      const uhaptics::Vec2 tau = scene.tool->getFingerJointTorque();  // the contact, this frame
      const uhaptics::Vec2 sent = device->getFingerJointTorque();
      const double scale = sent.dot(tau) / tau.squaredNorm();
      INFO("frame " << i << ": scale " << scale << " after " << elapsed << " s");
      CHECK((sent - scale * tau).norm() <= 1e-12 * tau.norm());  // only scaled, never turned
      CHECK(scale >= previous);                                  // rising
      // No faster than the ramp; 1 us for CHAI3D's clock (steady_clock too) read as a double of
      // the time since boot, a few 1e-10 s of rounding.
      CHECK(scale <= (elapsed + 1e-6) / rise);
      previous = scale;
    }
    CHECK(previous > 0.0);
    CHECK(previous < 0.01);  // held back: the full torque would be scale 1
  }
  SECTION("after the rise time, the full torque") {
    const double rise = 0.02;  // s
    scene.tool->setUseForceRise(true);
    scene.tool->setRiseTime(rise);
    const auto t0 = std::chrono::steady_clock::now();
    REQUIRE(scene.tool->setForcesON());
    scene.tick();
    CHECK(device->getFingerJointTorque().norm() < scene.tool->getFingerJointTorque().norm());  // rising
    // Frames until the rise time has surely passed (the outcome does not depend on how long they take).
    while (secondsSince(t0) < 2.0 * rise) {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
      scene.tick();
    }
    scene.tick();
    CHECK(device->getFingerJointTorque() == scene.tool->getFingerJointTorque());  // scale exactly 1
  }
}

// A contact the tool sends as joint torque only (no Cartesian force) is still a proxy contact.
TEST_CASE("exo finger tool: the device's renderer figures count the tool's contacts", "[chai3d][exo_tool]") {
  auto device = cExoFingerDevice::create(fingerToolSelection(true));
  device->setLockStep(true);
  FingerScene scene(device);
  scene.addBlockUnderCentre(device->getSpecifications().m_workspaceRadius);
  REQUIRE(scene.tool->start());
  std::uint64_t torque_frames = 0;
  for (int i = 0; i < 2000; ++i) {  // one lap: the finger dips into the block
    scene.tick();
    torque_frames += device->getFingerJointTorque().isZero(0.0) ? 0 : 1;
  }
  const auto stats = device->getSessionStats();
  REQUIRE(stats.faults == 0);
  const auto* solves = stats.figure("proxy_solves");
  const auto* contact_ticks = stats.figure("proxy_contact_ticks");
  REQUIRE(solves != nullptr);
  REQUIRE(contact_ticks != nullptr);
  INFO("frames with a joint torque " << torque_frames << ", solves " << solves->value << ", contact ticks "
                                     << contact_ticks->value);
  CHECK(torque_frames > 100);
  CHECK(solves->value == static_cast<double>(torque_frames));  // one solve per frame with a torque
  // Most of them above the contact threshold; the few below are the proxy's first and last
  // hundredths of a millimetre in the block.
  CHECK(contact_ticks->value <= solves->value);
  CHECK(contact_ticks->value > 0.5 * solves->value);
}

TEST_CASE("exo finger tool: a haptic frame allocates nothing", "[chai3d][exo_tool]") {
  auto device = cExoFingerDevice::create(fingerToolSelection(true));
  device->setLockStep(true);
  FingerScene scene(device);
  scene.addBlockUnderCentre(device->getSpecifications().m_workspaceRadius, true);
  REQUIRE(scene.tool->start());
  for (int i = 0; i < 2000; ++i) scene.tick();  // one full lap: every contact configuration seen once
  uhaptics::tools::AllocationScope scope;
  int contact_frames = 0;
  for (int i = 0; i < 2000; ++i) {
    scene.tool->updateFromDevice();
    scene.tool->computeInteractionForces();
    scene.tool->applyToDevice();
    contact_frames += scene.tool->getFingerJointTorque().isZero(0.0) ? 0 : 1;
  }
  const std::uint64_t allocations = scope.count();  // before any assertion (Catch may allocate)
  CHECK(contact_frames > 100);  // the count covers contact frames, not only free space
  CHECK(allocations == 0);
}
