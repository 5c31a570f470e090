// uhaptics-scene-rhi: palpation with the 4-DoF planar redundant interface (paper 003). A tissue
// block with a stiff region (left) and a soft one (right) is pressed by a stock cToolCursor; the
// device renders J^T F and uses its two degrees of self-motion to reshape its force-manipulability
// ellipse (FME) without changing the force: light in free motion, strong along the force on stiff
// tissue. The ellipse of the current configuration is drawn live at the tool (forces the motors can
// produce within their torque limits, in the device's y-z plane); [m] cycles the null-space mode
// (auto / free ellipse / stiff ellipse) through cRedundantPlanarDevice::setNullSpaceOptions.
//
//   uhaptics-scene-rhi                                    interactive ([m] mode, q quits)
//   uhaptics-scene-rhi --frames 300 --screenshot rhi.png   bounded run; exit 1 unless both regions
//                                                          were touched, the ellipse left its free
//                                                          shape on stiff tissue, and no tick faulted
//   UHAPTICS_CONFIG=cfg.json uhaptics-scene-rhi ...        device options from "options/rhi/..." in cfg.json
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "scene_app.hpp"  // first: CHAI3D (GLEW) before GLFW
#include <GLFW/glfw3.h>

#include "uhaptics/chai3d/CRedundantPlanarDevice.hpp"
#include "uhaptics/core/decompositions.hpp"
#include "uhaptics/core/force_manipulability.hpp"

using namespace chai3d;

namespace {

using Model = cRedundantPlanarDevice::Model;

const char* modeName(uhaptics::FmeEllipsoidMode a_mode) {
  switch (a_mode) {
    case uhaptics::FmeEllipsoidMode::kFree: return "free ellipse (fixed)";
    case uhaptics::FmeEllipsoidMode::kStiff: return "stiff ellipse (fixed)";
    default: return "auto (free in motion, stiff on stiff contact)";
  }
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const uhaptics::scenes::SceneOptions options = uhaptics::scenes::SceneOptions::parse(argc, argv);
    // Device options (e.g. options/rhi/limit_gain) may come from a UHAPTICS_CONFIG file.
    uhaptics::DeviceSelection selection;
    if (std::getenv("UHAPTICS_CONFIG"))
      selection = uhaptics::readDeviceSelection({"rhi"}, {"sim"}, [](const char* a_name) { return std::getenv(a_name); });
    selection.device = "rhi";
    // Palpation: press the stiff region (left), lift, move over, press the soft region (right).
    selection.hand.waypoints = {uhaptics::Vec3(0.0, -0.4, 0.1), uhaptics::Vec3(0.0, -0.4, -0.55),
                                uhaptics::Vec3(0.0, -0.4, 0.1), uhaptics::Vec3(0.0, 0.4, 0.1),
                                uhaptics::Vec3(0.0, 0.4, -0.55), uhaptics::Vec3(0.0, 0.4, 0.1)};
    selection.hand.lap_time = 6.0;
    auto device = cRedundantPlanarDevice::create(selection);
    device->setLockStep(options.bounded());
    const cHapticDeviceInfo info = device->getSpecifications();
    const double r = info.m_workspaceRadius;
    const Model& model = device->getModel();

    uhaptics::scenes::SceneApp app("uhaptics: RHI palpation, force-manipulability ellipse", options);
    cWorld* world = app.world();
    app.camera()->set(cVector3d(0.45, 0.0, 0.0), cVector3d(0.0, 0.0, -0.02), cVector3d(0.0, 0.0, 1.0));
    app.camera()->setClippingPlanes(0.01, 5.0);

    auto* tool = new cToolCursor(world);
    world->addChild(tool);
    tool->setHapticDevice(device);
    tool->setWorkspaceRadius(r);  // world coordinates = device coordinates (m)
    tool->setRadius(0.004);

    // Tissue: top surface at z = -0.2 r; stiff (paper 003's K_e = 1000 N/m) on the left, soft on the right.
    const double stiffness = info.m_maxLinearStiffness;
    auto* stiff = new cMesh();
    world->addChild(stiff);
    cCreateBox(stiff, 0.06, 0.08, 0.05, cVector3d(0.0, -0.04, -0.2 * r - 0.025));
    stiff->m_material->setRedFireBrick();
    stiff->m_material->setStiffness(stiffness);
    stiff->createAABBCollisionDetector(0.004);
    auto* soft = new cMesh();
    world->addChild(soft);
    cCreateBox(soft, 0.06, 0.08, 0.05, cVector3d(0.0, 0.04, -0.2 * r - 0.025));
    soft->m_material->setPinkLight();
    soft->m_material->setStiffness(0.1 * stiffness);
    soft->createAABBCollisionDetector(0.004);

    // The ellipse: a flat ellipsoid in the y-z plane, scaled so the free-motion ellipse at home has
    // a 0.3 r major semi-axis; and the linkage as its equivalent serial chain (links at their
    // absolute angles, chained from the base).
    auto* ellipse = new cShapeEllipsoid(0.001, 0.01, 0.01);
    world->addChild(ellipse);
    ellipse->m_material->setBlueCornflower();
    ellipse->setUseTransparency(true);
    ellipse->setTransparencyLevel(0.5f);
    const Model::JointVector inv_limits_sq = uhaptics::fme::inverseSquaredLimits<4>(model.effortLimits());
    uhaptics::Mat2 home_fme;
    Model::Jacobian J;
    model.jacobian(model.homeJoints(), J);
    if (!uhaptics::fme::weightedFme<2, 4>(J, inv_limits_sq, home_fme)) throw uhaptics::Error("RHI singular at home");
    uhaptics::Vec2 home_axes;  // ascending
    uhaptics::symmetricEigen(home_fme, home_axes);
    const double axis_scale = 0.3 * r / std::sqrt(home_axes(1));
    std::array<cShapeLine*, 4> links{};
    for (auto& link : links) {
      link = new cShapeLine(cVector3d(0, 0, 0), cVector3d(0, 0, 0));
      world->addChild(link);
      link->setLineWidth(4.0);
      link->m_colorPointA.setGrayDim();
      link->m_colorPointB.setGrayDim();
    }
    uhaptics::Vec2 home_tip;
    model.forward(model.homeJoints(), home_tip);

    if (!tool->start()) {
      std::fprintf(stderr, "uhaptics-scene-rhi: the device did not open\n");
      return 1;
    }

    std::atomic<double> peak_stiff{0.0}, peak_soft{0.0};
    std::atomic<double> min_omega{1.0};
    cHapticPoint* point = tool->getHapticPoint(0);
    auto haptic_frame = [&] {
      world->computeGlobalPositions(true);
      tool->updateFromDevice();
      tool->computeInteractionForces();
      tool->applyToDevice();
      const double force = tool->getDeviceGlobalForce().length();
      if (point->isInContact(stiff)) uhaptics::scenes::recordPeak(peak_stiff, force);
      if (point->isInContact(soft)) uhaptics::scenes::recordPeak(peak_soft, force);
    };

    uhaptics::FmeEllipsoidMode mode = device->getNullSpaceOptions().mode;
    app.onKey([&](int a_key) {
      if (a_key != GLFW_KEY_M) return;
      auto o = device->getNullSpaceOptions();
      o.mode = o.mode == uhaptics::FmeEllipsoidMode::kAuto    ? uhaptics::FmeEllipsoidMode::kFree
               : o.mode == uhaptics::FmeEllipsoidMode::kFree ? uhaptics::FmeEllipsoidMode::kStiff
                                                              : uhaptics::FmeEllipsoidMode::kAuto;
      if (device->setNullSpaceOptions(o)) mode = o.mode;
    });
    cLabel* title = app.addLabel(10, 470);
    title->setText("RHI: J^T F + force-manipulability null-space control   [m] ellipse mode   [q] quit");
    cLabel* mode_label = app.addLabel(10, 445);
    cLabel* status_label = app.addLabel(10, 420);
    cLabel* touch_label = app.addLabel(10, 395);
    auto graphics_frame = [&] {
      const Model::JointVector q = device->getJointPositions();
      const auto status = device->getNullSpaceStatus();
      double omega = status.omega;
      double seen = min_omega.load();
      while (omega < seen && !min_omega.compare_exchange_weak(seen, omega)) {
      }
      // Links: x_k = base + sum_{i <= k} d_i e(phi_i), mapped like the device maps its task plane
      // (task x -> +y, task y -> -z, origin at the home end effector).
      const auto& p = model.parameters();
      const Model::JointVector phi = p.coupling * q + p.angle_offset;
      uhaptics::Vec2 joint = p.base;
      for (int i = 0; i < 4; ++i) {
        const uhaptics::Vec2 next = joint + p.link_length(i) * uhaptics::Vec2(std::cos(phi(i)), std::sin(phi(i)));
        links[static_cast<size_t>(i)]->m_pointA = cVector3d(0.0, joint.x() - home_tip.x(), -(joint.y() - home_tip.y()));
        links[static_cast<size_t>(i)]->m_pointB = cVector3d(0.0, next.x() - home_tip.x(), -(next.y() - home_tip.y()));
        joint = next;
      }
      // FME of this configuration: semi-axes sqrt(eig(M_hat)) along its eigenvectors.
      Model::Jacobian Jq;
      model.jacobian(q, Jq);
      uhaptics::Mat2 fme;
      if (uhaptics::fme::weightedFme<2, 4>(Jq, inv_limits_sq, fme)) {
        uhaptics::Vec2 axes;  // ascending
        uhaptics::Mat2 directions;
        uhaptics::symmetricEigen(fme, axes, &directions);
        const uhaptics::Vec2 major = directions.col(1);
        const double angle = std::atan2(-major.y(), major.x());  // task -> device (y, z) plane
        ellipse->setRadii(0.0005, axis_scale * std::sqrt(axes(1)), axis_scale * std::sqrt(axes(0)));
        cMatrix3d R;
        R.setAxisAngleRotationRad(cVector3d(1, 0, 0), angle);
        ellipse->setLocalRot(R);
        ellipse->setLocalPos(tool->getDeviceGlobalPos() + cVector3d(0.01, 0.0, 0.0));  // just in front of the tool
      }
      mode_label->setText(std::string("null-space mode: ") + modeName(mode) + "   ellipse activation omega " +
                          cStr(status.omega, 2) + " (1 free, 0 stiff)");
      status_label->setText("tool force " + cStr(tool->getDeviceGlobalForce().length(), 2) + " N,  force scaling alpha " +
                            cStr(status.alpha, 2) + ",  null-space torque " + cStr(status.tau_null.norm(), 3) + " N m");
      touch_label->setText("peak palpation force: stiff region " + cStr(peak_stiff.load(), 2) + " N, soft region " +
                           cStr(peak_soft.load(), 2) + " N");
    };
    app.run(haptic_frame, uhaptics::scenes::hapticFramesPerFixedStep(device->getServoPeriod()), graphics_frame);
    tool->stop();

    const auto stats = device->getSessionStats();
    std::printf("uhaptics-scene-rhi: %d frames, %llu servo ticks, peak force stiff %.2f N / soft %.2f N, lowest "
                "ellipse activation %.2f, %llu faults\n",
                app.framesRendered(), static_cast<unsigned long long>(stats.ticks), peak_stiff.load(), peak_soft.load(),
                min_omega.load(), static_cast<unsigned long long>(stats.faults));
    if (options.bounded() &&
        (peak_stiff.load() <= 0.0 || peak_soft.load() <= 0.0 || min_omega.load() > 0.5 || stats.faults > 0)) {
      std::fprintf(stderr, "uhaptics-scene-rhi: expected both regions palpated, the stiff ellipse engaged, no faults\n");
      return 1;
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "uhaptics-scene-rhi: %s\n", e.what());
    return 2;
  }
}
