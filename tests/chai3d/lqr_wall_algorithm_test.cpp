// cAlgorithmLqrWall: the LQR wall in a haptic point's pipeline, against a rigid mesh, on the
// simulated TAU device (no graphics).
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>

#include "chai3d.h"
#include "tau_push.hpp"
#include "uhaptics/chai3d/CAlgorithmLqrWall.hpp"
#include "uhaptics/tools/alloc_probe.hpp"

using namespace chai3d;

namespace {

constexpr double kToolRadius = 0.001;  // m

// Wall mode "spring" in the push (tau_push.hpp): the device never engages the LQR wall on its own, so
// whatever LQR contact happens comes from the algorithm.
uhaptics::DeviceSelection tauSelection() { return tauPushSelection(cTauDevice::C_TAU_WALL_SPRING); }

struct WallRun {
  double max_penetration = 0.0;  // m, tool centre below the proxy's contact plane
  bool lqr_engaged = false;
  int surface_frames = 0;
  double worst_normal_dot = 1.0;  // smallest n . (0, 0, 1) over frames with an active surface
  double worst_point_z = 0.0;     // largest |z - top| of the surface point
};

struct TauScene {
  cWorld world;
  cToolCursor* tool = nullptr;
  cAlgorithmLqrWall* wall = nullptr;
  cTauDevicePtr device;
  double top = 0.0;  // z of the plane the proxy centre slides on (face + tool radius)
  // brute_force: CHAI3D's brute-force collision detector instead of its AABB tree, whose every
  // query allocates a traversal stack (CCollisionAABB::computeCollision); used where allocations
  // are counted, so that the count is ours.
  explicit TauScene(bool with_algorithm, bool brute_force = false) : device(cTauDevice::create(tauSelection())) {
    device->setLockStep(true);
    const double r = device->getSpecifications().m_workspaceRadius;
    // A rigid mesh: a box whose top face is 0.2 workspace radii below the centre.
    cMesh* block = new cMesh();
    world.addChild(block);
    cCreateBox(block, 4 * r, 4 * r, 2 * r);
    block->setLocalPos(0.0, 0.0, -1.2 * r);
    if (brute_force) block->createBruteForceCollisionDetector();
    else block->createAABBCollisionDetector(kToolRadius);
    block->m_material->setStiffness(device->getSpecifications().m_maxLinearStiffness);
    top = -0.2 * r + kToolRadius;
    tool = new cToolCursor(&world);
    world.addChild(tool);
    tool->setHapticDevice(device);
    tool->setRadius(kToolRadius);
    tool->setWorkspaceRadius(r);
    if (with_algorithm) wall = cAlgorithmLqrWall::install(tool->getHapticPoint(0), device);
  }
  void tick() {
    world.computeGlobalPositions(true);
    tool->updateFromDevice();
    tool->computeInteractionForces();
    tool->applyToDevice();
  }
  WallRun run(int frames) {
    WallRun result;
    for (int i = 0; i < frames; ++i) {
      tick();
      result.max_penetration = std::max(result.max_penetration, top - tool->getDeviceGlobalPos().z());
      result.lqr_engaged = result.lqr_engaged || device->isLqrWallEngaged();
      if (wall != nullptr && wall->isSurfaceActive()) {
        ++result.surface_frames;
        result.worst_normal_dot = std::min(result.worst_normal_dot, wall->getSurfaceNormal().z());
        result.worst_point_z = std::max(result.worst_point_z, std::abs(wall->getSurfacePoint().z() - top));
      }
      REQUIRE(device->getLastFault() == uhaptics::Fault::kNone);
    }
    return result;
  }
};

}  // namespace

TEST_CASE("LQR wall algorithm: a 12 N push into a rigid mesh stays under 1 mm, the spring does not",
          "[chai3d][lqr_algorithm]") {
  TauScene lqr_scene(true);
  REQUIRE(lqr_scene.tool->start());
  const WallRun lqr = lqr_scene.run(4000);  // two laps of the hand: two pushes
  INFO("LQR: max penetration " << lqr.max_penetration * 1e3 << " mm");
  CHECK(lqr.lqr_engaged);
  CHECK(lqr.surface_frames > 500);  // the hand pushes for about half of each lap
  // The surface comes from CHAI3D's proxy: the box's top face, to the proxy's epsilon (1e-4 m).
  CHECK(lqr.worst_normal_dot > 0.999);
  CHECK(lqr.worst_point_z < 2e-4);
  CHECK(lqr.max_penetration > 0.0);
  CHECK(lqr.max_penetration < 1e-3);  // paper 001: maximum penetration below 1 mm

  // The same scene with the algorithm off: CHAI3D's spring at 6000 N/m sinks F / k = 2 mm.
  TauScene spring_scene(true);
  spring_scene.wall->setEnabled(false);
  REQUIRE(spring_scene.tool->start());
  const WallRun spring = spring_scene.run(4000);
  INFO("spring: max penetration " << spring.max_penetration * 1e3 << " mm");
  if (std::getenv("UHAPTICS_TEST_REPORT") != nullptr)
    WARN("max penetration: LQR " << lqr.max_penetration * 1e3 << " mm, spring " << spring.max_penetration * 1e3 << " mm");
  CHECK_FALSE(spring.lqr_engaged);
  CHECK(spring.max_penetration > 1.5e-3);
  CHECK(spring.max_penetration > 2.0 * lqr.max_penetration);
}

TEST_CASE("LQR wall algorithm: switching it off mid-contact hands back to the spring",
          "[chai3d][lqr_algorithm]") {
  TauScene scene(true);
  REQUIRE(scene.tool->start());
  // Into the first push (the hand reaches the block about 0.3 s into the lap) until the wall holds.
  int frames = 0;
  while (!scene.device->isLqrWallEngaged() && frames < 2000) {
    scene.tick();
    ++frames;
  }
  REQUIRE(scene.device->isLqrWallEngaged());
  scene.run(100);
  scene.wall->setEnabled(false);
  scene.tick();
  CHECK_FALSE(scene.device->isLqrWallEngaged());
  CHECK_FALSE(scene.wall->isSurfaceActive());
  scene.wall->setEnabled(true);
  scene.run(200);
  CHECK(scene.device->isLqrWallEngaged());  // still pushed: the wall takes the contact again
}

TEST_CASE("LQR wall algorithm: a haptic frame allocates nothing", "[chai3d][lqr_algorithm]") {
  TauScene scene(true, true);
  REQUIRE(scene.tool->start());
  const WallRun warm = scene.run(1000);  // through free space and into the first push
  REQUIRE(warm.lqr_engaged);
  uhaptics::tools::AllocationScope scope;
  for (int i = 0; i < 2000; ++i) {  // the rest of the push, release, free space, next push
    scene.tool->updateFromDevice();
    scene.tool->computeInteractionForces();
    scene.tool->applyToDevice();
  }
  CHECK(scope.count() == 0);
}
