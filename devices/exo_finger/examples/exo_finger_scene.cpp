// uhaptics-scene-exo: the finger exoskeleton (paper 000) touching a soft and a rigid object with
// the multi-point finger tool (cExoFingerTool): every phalanx point has CHAI3D's finger proxy, the
// contacts become virtual-finger joint torques, and the device shows their projection onto its one
// actuated joint (subspace proxy). The simulated finger flexes and extends on its own (scripted
// hand), so the scene runs unattended.
//
//   uhaptics-scene-exo                                   interactive (q quits)
//   uhaptics-scene-exo --frames 300 --screenshot exo.png  bounded run; exit 1 unless both objects
//                                                         were touched and no tick faulted
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>

#include "scene_app.hpp"  // first: CHAI3D (GLEW) before GLFW
#include <GLFW/glfw3.h>
#include "uhaptics/chai3d/CExoFingerTool.hpp"

using namespace chai3d;

namespace {

// Peak force per object, written by the haptic loop and read by the graphics loop.
struct Touches {
  std::atomic<double> soft{0.0}, rigid{0.0};
};

}  // namespace

int main(int argc, char** argv) {
  try {
    const uhaptics::scenes::SceneOptions options = uhaptics::scenes::SceneOptions::parse(argc, argv);
    uhaptics::DeviceSelection selection;
    selection.device = "exo";
    selection.hand.lap_time = 4.0;  // one flexion-extension of the MCP every 4 s
    auto device = cExoFingerDevice::create(selection);
    device->setLockStep(options.bounded());
    const cHapticDeviceInfo info = device->getSpecifications();

    uhaptics::scenes::SceneApp app("uhaptics: finger exoskeleton, multi-point finger", options);
    cWorld* world = app.world();
    // The finger moves in the device's y-z plane: look at it along -x, the fingertip pointing right.
    app.camera()->set(cVector3d(0.2, 0.0, 0.006), cVector3d(0.0, 0.0, 0.006), cVector3d(0.0, 0.0, 1.0));
    app.camera()->setClippingPlanes(0.01, 1.0);

    auto* tool = new cExoFingerTool(world);
    world->addChild(tool);
    tool->setExoFingerDevice(device);
    tool->setWorkspaceRadius(info.m_workspaceRadius);  // world coordinates = device coordinates (m)
    tool->setRadius(0.0025, 0.0015);                    // display, contact

    // Rigid block under the palm side, reached by the middle phalanx in deep flexion; a soft pad in
    // front of the fingertip, reached half way through flexion.
    const double stiffness = info.m_maxLinearStiffness;
    auto* rigid = new cMesh();
    world->addChild(rigid);
    cCreateBox(rigid, 0.03, 0.05, 0.02, cVector3d(0.0, -0.03, -0.036));
    rigid->m_material->setBlueSteel();
    rigid->m_material->setStiffness(stiffness);
    rigid->createAABBCollisionDetector(0.0015);
    auto* soft = new cMesh();
    world->addChild(soft);
    cCreateSphere(soft, 0.010, 32, 32, cVector3d(0.0, 0.040, -0.010));
    soft->m_material->setPinkHot();
    soft->m_material->setStiffness(0.15 * stiffness);
    soft->createAABBCollisionDetector(0.0015);

    if (!tool->start()) {
      std::fprintf(stderr, "uhaptics-scene-exo: the device did not open\n");
      return 1;
    }

    Touches touches;
    auto haptic_frame = [&] {
      world->computeGlobalPositions(true);
      tool->updateFromDevice();
      tool->computeInteractionForces();
      tool->applyToDevice();
      for (int i = 0; i < tool->getNumHapticPoints(); ++i) {
        cHapticPoint* point = tool->getHapticPoint(i);
        const double force = tool->getPointGlobalForce(i).length();
        if (point->isInContact(soft)) uhaptics::scenes::recordPeak(touches.soft, force);
        if (point->isInContact(rigid)) uhaptics::scenes::recordPeak(touches.rigid, force);
      }
    };

    cLabel* title = app.addLabel(10, 470);
    title->setText("finger exoskeleton: subspace proxy, multi-point finger tool (" + std::to_string(tool->getNumHapticPoints()) +
                   " finger-proxy points)   [q] quit");
    cLabel* angles = app.addLabel(10, 445);
    cLabel* torque = app.addLabel(10, 420);
    cLabel* touched = app.addLabel(10, 395);
    auto graphics_frame = [&] {
      const uhaptics::Vec2 x = device->getFingerAngles();
      const uhaptics::Vec2 tau = tool->getFingerJointTorque();
      angles->setText("MCP " + cStr(cRadToDeg(x(0)), 0) + " deg   PIP " + cStr(cRadToDeg(x(1)), 0) + " deg");
      torque->setText("virtual-finger torque (MCP, PIP) = (" + cStr(tau(0) * 1e3, 1) + ", " + cStr(tau(1) * 1e3, 1) +
                      ") mN m   ->   actuator force " + cStr(device->getActuatorForce(), 2) + " N");
      touched->setText("peak contact force: soft pad " + cStr(touches.soft.load(), 2) + " N, rigid block " +
                       cStr(touches.rigid.load(), 2) + " N");
    };
    app.run(haptic_frame, uhaptics::scenes::hapticFramesPerFixedStep(device->getServoPeriod()), graphics_frame);
    tool->stop();

    const auto stats = device->getSessionStats();
    std::printf("uhaptics-scene-exo: %d frames, %llu servo ticks, peak contact force soft %.2f N / rigid %.2f N, "
                "%llu faults\n",
                app.framesRendered(), static_cast<unsigned long long>(stats.ticks), touches.soft.load(),
                touches.rigid.load(), static_cast<unsigned long long>(stats.faults));
    if (options.bounded() && (touches.soft.load() <= 0.0 || touches.rigid.load() <= 0.0 || stats.faults > 0)) {
      std::fprintf(stderr, "uhaptics-scene-exo: the finger did not touch both objects without faults\n");
      return 1;
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "uhaptics-scene-exo: %s\n", e.what());
    return 2;
  }
}
