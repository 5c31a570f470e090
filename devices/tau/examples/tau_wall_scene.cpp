// uhaptics-scene-tau: the TAU device (paper 001) pressing on a stiff wall and on a tooth-like rigid
// mesh. The tool's haptic point runs CHAI3D's finger proxy with the LQR wall behind it
// (cAlgorithmLqrWall); [l] switches between the LQR wall and CHAI3D's plain spring (6000 N/m, the
// paper's baseline) at run time. The penetration below the surface is shown live, with the peak of
// the last contact per renderer: the paper's bound is 1 mm. The scripted hand presses with up to
// 12 N, alternately on the wall and on the tooth.
//
//   uhaptics-scene-tau                                    interactive ([l] LQR / spring, q quits)
//   uhaptics-scene-tau --frames 300 --screenshot tau.png   bounded run (LQR wall); exit 1 unless
//                                                          both objects were touched, the LQR wall
//                                                          held and the penetration stayed < 1 mm
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>

#include "scene_app.hpp"  // first: CHAI3D (GLEW) before GLFW
#include <GLFW/glfw3.h>
#include "uhaptics/chai3d/CAlgorithmLqrWall.hpp"

using namespace chai3d;

namespace {

constexpr double kToolRadius = 0.001;  // m: a dental probe's tip

// A molar-like crown on two tapering roots, z up: a flattened ellipsoid with four overlapping cusps
// around a central fossa (a hollow, so a probe pressed on the occlusal surface settles in it).
void createTooth(cMesh* a_mesh, const cVector3d& a_crownCentre) {
  const cColorf enamel(0.95f, 0.93f, 0.85f);
  cCreateEllipsoid(a_mesh, 0.0058, 0.0062, 0.0035, 32, 24, a_crownCentre, cIdentity3d(), enamel);
  for (const double dx : {-0.0019, 0.0019}) {
    for (const double dy : {-0.0021, 0.0021}) {
      cCreateSphere(a_mesh, 0.0026, 20, 20, a_crownCentre + cVector3d(dx, dy, 0.0016), cIdentity3d(), enamel);
    }
  }
  cMatrix3d down;
  down.setAxisAngleRotationDeg(cVector3d(1, 0, 0), 180.0);
  for (const double dy : {-0.0028, 0.0028}) {
    cCreateCone(a_mesh, 0.011, 0.0026, 0.0008, 16, 1, 1, false, true, a_crownCentre + cVector3d(0.0, dy, -0.002), down,
                enamel);
  }
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const uhaptics::scenes::SceneOptions options = uhaptics::scenes::SceneOptions::parse(argc, argv);
    uhaptics::DeviceSelection selection;
    selection.device = "tau";
    // Wall mode spring: the LQR wall comes only from the algorithm (so [l] really switches).
    selection.options["wall"] = cTauDevice::C_TAU_WALL_SPRING;
    // The hand: down onto the wall (left), up, over, down onto the tooth (right), up, back. Paper
    // 001's users press with 8-15 N: a stiff hand spring saturating at 12 N, led below the surfaces.
    selection.hand.waypoints = {uhaptics::Vec3(0.0, -0.36, 0.3), uhaptics::Vec3(0.0, -0.36, -0.8),
                                uhaptics::Vec3(0.0, -0.36, 0.3), uhaptics::Vec3(0.0, 0.2, 0.3),
                                uhaptics::Vec3(0.0, 0.2, -0.6), uhaptics::Vec3(0.0, 0.2, 0.3)};
    selection.hand.lap_time = 6.0;
    selection.hand.stiffness = 1500.0;
    selection.hand.damping = 20.0;
    selection.hand.max_force = 12.0;
    auto device = cTauDevice::create(selection);
    device->setLockStep(options.bounded());
    const cHapticDeviceInfo info = device->getSpecifications();
    const double r = info.m_workspaceRadius;

    uhaptics::scenes::SceneApp app("uhaptics: TAU, LQR wall vs spring", options);
    cWorld* world = app.world();
    app.camera()->set(cVector3d(0.065, 0.0, 0.02), cVector3d(0.0, -0.001, -0.009), cVector3d(0.0, 0.0, 1.0));
    app.camera()->setClippingPlanes(0.005, 1.0);

    auto* tool = new cToolCursor(world);
    world->addChild(tool);
    tool->setHapticDevice(device);
    tool->setWorkspaceRadius(r);  // world coordinates = device coordinates (m)
    tool->setRadius(kToolRadius);
    tool->setShowContactPoints(true, true);  // proxy and goal: the penetration is the gap between them
    cAlgorithmLqrWall* lqr = cAlgorithmLqrWall::install(tool->getHapticPoint(0), device);

    const double stiffness = info.m_maxLinearStiffness;  // 6000 N/m: the spring baseline
    auto* wall = new cMesh();
    world->addChild(wall);
    cCreateBox(wall, 0.02, 0.012, 0.01, cVector3d(0.0, -0.36 * r, -0.3 * r - 0.005));  // top face at z = -0.3 r
    wall->m_material->setBlueSteel();
    wall->m_material->setStiffness(stiffness);
    wall->createAABBCollisionDetector(kToolRadius);
    auto* tooth = new cMesh();
    world->addChild(tooth);
    createTooth(tooth, cVector3d(0.0, 0.2 * r, -0.3 * r - 0.0042));  // cusp tops near z = -0.3 r
    tooth->m_material->setStiffness(stiffness);
    tooth->m_material->setWhiteIvory();
    tooth->createAABBCollisionDetector(kToolRadius);

    if (!tool->start()) {
      std::fprintf(stderr, "uhaptics-scene-tau: the device did not open\n");
      return 1;
    }

    // Penetration: the goal's depth below the proxy, along the touched faces' normal.
    std::atomic<double> penetration{0.0}, peak_lqr{0.0}, peak_spring{0.0}, peak_episode{0.0};
    std::atomic<bool> touched_wall{false}, touched_tooth{false}, lqr_held{false};
    cHapticPoint* point = tool->getHapticPoint(0);
    bool in_contact = false;
    auto haptic_frame = [&] {
      world->computeGlobalPositions(true);
      tool->updateFromDevice();
      tool->computeInteractionForces();
      tool->applyToDevice();
      double depth = 0.0;
      if (point->getNumCollisionEvents() > 0) {
        cVector3d normal(0, 0, 0);
        for (int i = 0; i < point->getNumCollisionEvents(); ++i) normal.add(point->getCollisionEvent(i)->m_globalNormal);
        if (normal.length() > 0.0) depth = std::max(0.0, cDot(point->getGlobalPosProxy() - point->getGlobalPosGoal(), cNormalize(normal)));
        if (point->isInContact(wall)) touched_wall = true;
        if (point->isInContact(tooth)) touched_tooth = true;
        if (!in_contact) peak_episode = 0.0;
        in_contact = true;
        uhaptics::scenes::recordPeak(peak_episode, depth);
        uhaptics::scenes::recordPeak(lqr->getEnabled() ? peak_lqr : peak_spring, depth);
      } else {
        in_contact = false;
      }
      if (device->isLqrWallEngaged()) lqr_held = true;
      penetration = depth;
    };

    app.onKey([&](int a_key) {
      if (a_key == GLFW_KEY_L) lqr->setEnabled(!lqr->getEnabled());
    });
    cLabel* title = app.addLabel(10, 470);
    title->setText("TAU: CHAI3D finger proxy + LQR wall (cAlgorithmLqrWall)   [l] LQR wall / spring   [q] quit");
    cLabel* mode = app.addLabel(10, 445);
    cLabel* depth = app.addLabel(10, 420);
    cLabel* peaks = app.addLabel(10, 395);
    auto graphics_frame = [&] {
      mode->setText(std::string("renderer: ") +
                    (lqr->getEnabled() ? (device->isLqrWallEngaged() ? "LQR wall (holding)" : "LQR wall (free space)")
                                       : "spring 6000 N/m (CHAI3D proxy)"));
      depth->setText("penetration " + cStr(penetration.load() * 1e3, 2) + " mm   (this contact: peak " +
                     cStr(peak_episode.load() * 1e3, 2) + " mm; paper 001's bound: 1 mm)");
      peaks->setText("peak penetration so far: LQR wall " + cStr(peak_lqr.load() * 1e3, 2) + " mm, spring " +
                     cStr(peak_spring.load() * 1e3, 2) + " mm");
    };
    app.run(haptic_frame, uhaptics::scenes::hapticFramesPerFixedStep(device->getServoPeriod()), graphics_frame);
    tool->stop();

    const auto stats = device->getSessionStats();
    std::printf("uhaptics-scene-tau: %d frames, %llu servo ticks, touched wall %d tooth %d, LQR held %d, "
                "peak penetration LQR %.3f mm / spring %.3f mm, %llu faults\n",
                app.framesRendered(), static_cast<unsigned long long>(stats.ticks), touched_wall.load() ? 1 : 0,
                touched_tooth.load() ? 1 : 0, lqr_held.load() ? 1 : 0, peak_lqr.load() * 1e3, peak_spring.load() * 1e3,
                static_cast<unsigned long long>(stats.faults));
    if (options.bounded() &&
        (!touched_wall.load() || !touched_tooth.load() || !lqr_held.load() || peak_lqr.load() >= 1e-3 || stats.faults > 0)) {
      std::fprintf(stderr, "uhaptics-scene-tau: expected both objects touched, the LQR wall holding under 1 mm, no faults\n");
      return 1;
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "uhaptics-scene-tau: %s\n", e.what());
    return 2;
  }
}
