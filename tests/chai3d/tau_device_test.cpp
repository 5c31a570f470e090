// cTauDevice on the simulated backend with a stock CHAI3D world and cToolCursor (no graphics).
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <utility>
#include <vector>

#include "chai3d.h"
#include "tau_push.hpp"
#include "tool_scene.hpp"
#include "uhaptics/chai3d/CTauDevice.hpp"
#include "uhaptics/tools/alloc_probe.hpp"

using namespace chai3d;

namespace {

constexpr double kToolRadius = 0.001;  // m

uhaptics::DeviceSelection tauSelection(cTauDevice::cWallMode mode) { return tauPushSelection(mode); }

struct Result {
  double max_penetration = 0.0;  // m, tool centre below (surface + tool radius)
  bool lqr_engaged = false;
  std::uint64_t contacts = 0;
  uhaptics::RefereeReport referee;  // the plant's truth
};

// A rigid block (a mesh, CHAI3D's finger proxy) whose top face is 0.2 workspace radii below the
// centre; the hand pushes the tool into it for two laps.
Result pushIntoBlock(cTauDevice::cWallMode mode, double stiffness) {
  auto device = cTauDevice::create(tauSelection(mode));
  device->setLockStep(true);
  const double r = device->getSpecifications().m_workspaceRadius;
  ToolScene scene(device, kToolRadius);
  scene.addBlock(0.2, stiffness);
  cToolCursor* tool = scene.tool;
  REQUIRE(tool->start());
  const double surface = -0.2 * r + kToolRadius;
  Result result;
  for (int i = 0; i < 4000; ++i) {
    scene.tick();
    result.max_penetration = std::max(result.max_penetration, surface - tool->getDeviceGlobalPos().z());
    result.lqr_engaged = result.lqr_engaged || device->isLqrWallEngaged();
    REQUIRE(device->getLastFault() == uhaptics::Fault::kNone);
  }
  const uhaptics::SessionStatsSnapshot stats = device->getSessionStats();
  REQUIRE(stats.has_referee);
  CHECK_FALSE(stats.has_servo_timing);  // lock-step sim: no servo thread to time
  result.contacts = stats.contacts;
  result.referee = stats.referee;
  return result;
}

}  // namespace

TEST_CASE("tau: specification complete and consistent with the model", "[chai3d][tau]") {
  auto device = cTauDevice::create(tauSelection(cTauDevice::C_TAU_WALL_AUTO));
  const cHapticDeviceInfo info = device->getSpecifications();
  CHECK(info.m_model == C_HAPTIC_DEVICE_CUSTOM);
  CHECK_THAT(info.m_modelName, Catch::Contains("TAU"));
  CHECK(info.m_manufacturerName == "uhaptics");
  CHECK(info.m_maxLinearForce > 1.0);  // newtons from 2 N m joints on centimetre levers
  CHECK(info.m_maxAngularTorque > 0.0);
  CHECK(info.m_maxLinearStiffness == 6000.0);
  CHECK(info.m_workspaceRadius == Approx(0.025));  // paper 001: a 50 mm cube
  CHECK(info.m_sensedPosition);
  CHECK(info.m_sensedRotation);
  CHECK(info.m_actuatedPosition);
  CHECK(info.m_actuatedRotation);
  CHECK(info.m_maxGripperForce == 0.0);
  REQUIRE(device->open());
  cVector3d p;
  cMatrix3d R;
  device->getPosition(p);
  device->getRotation(R);
  CHECK(p.length() < 1e-3);  // starts at the workspace centre
  CHECK(cAbs(R.getCol0().dot(cVector3d(1, 0, 0)) - 1.0) < 1e-3);
  double q[C_MAX_DOF];
  CHECK(device->getJointAnglesRad(q));
  // On sim the command acts in its period: the undelayed rating limits the spring's takeover.
  CHECK(device->getSpringLimit() == 7370.0);  // tau.json: max_linear_stiffness at 1 kHz
}

TEST_CASE("tau: free space holds gravity, forces flow through J^T", "[chai3d][tau]") {
  auto selection = tauSelection(cTauDevice::C_TAU_WALL_SPRING);
  selection.hand_enabled = false;
  auto device = cTauDevice::create(selection);
  device->setLockStep(true);
  REQUIRE(device->open());
  cVector3d p;
  for (int i = 0; i < 500; ++i) device->setForce(cVector3d(0, 0, 0));
  device->getPosition(p);
  CHECK(p.length() < 1e-3);  // gravity compensated: no sag beyond a millimetre in 0.5 s
  // 1 N up for 30 ms, nothing holding it: it rises (a few millimetres, well inside the workspace).
  // The task-space inertia is not isotropic, so the velocity need not be exactly along the force;
  // it must be mostly upward.
  for (int i = 0; i < 30; ++i) device->setForce(cVector3d(0, 0, 1.0));
  cVector3d v;
  device->getLinearVelocity(v);
  INFO("velocity " << v.str(4));
  CHECK(v.z() > 0.01);
  CHECK(v.z() > 2.0 * std::max(std::abs(v.x()), std::abs(v.y())));
}

TEST_CASE("tau: the LQR wall holds a 12 N push against a rigid mesh under 1 mm, the spring does not",
          "[chai3d][tau]") {
  const Result lqr = pushIntoBlock(cTauDevice::C_TAU_WALL_AUTO, 6000.0);
  CHECK(lqr.lqr_engaged);
  CHECK(lqr.contacts >= 1);
  CHECK(lqr.max_penetration > 0.0);
  CHECK(lqr.max_penetration < 1e-3);  // paper 001: maximum penetration below 1 mm
  // The same push on the spring baseline sinks F / k = 12 / 6000 = 2 mm: the bound discriminates.
  const Result spring = pushIntoBlock(cTauDevice::C_TAU_WALL_SPRING, 6000.0);
  CHECK_FALSE(spring.lqr_engaged);
  CHECK(spring.max_penetration > 1.5e-3);
}

TEST_CASE("tau: the referee, from the plant's truth: the spring sinks F / k, the LQR wall holds 1 mm and is "
          "3x stiffer", "[chai3d][tau][referee]") {
  const Result spring = pushIntoBlock(cTauDevice::C_TAU_WALL_SPRING, 6000.0);
  const Result lqr = pushIntoBlock(cTauDevice::C_TAU_WALL_AUTO, 6000.0);
  const uhaptics::RefereeReport& s = spring.referee;
  const uhaptics::RefereeReport& l = lqr.referee;
  INFO("spring: " << s.max_true_penetration_mm << " mm, " << s.rendered_stiffness_N_per_m << " N/m, "
                  << s.generated_energy_mJ << " mJ, chatter " << s.chatter_N << " N; LQR: "
                  << l.max_true_penetration_mm << " mm, " << l.rendered_stiffness_N_per_m << " N/m, "
                  << l.generated_energy_mJ << " mJ, chatter " << l.chatter_N << " N");
  // The hand pushes 12 N (tau_push.hpp): a 6000 N/m spring holds it 2 mm deep and renders 6000 N/m,
  // within the encoders' 0.1 mm at the tool.
  CHECK(s.peak_user_force_N == Approx(12.0).epsilon(0.02));
  CHECK(s.max_true_penetration_mm == Approx(2.0).margin(0.2));
  CHECK(s.rendered_stiffness_N_per_m == Approx(6000.0).epsilon(0.1));
  CHECK(l.max_true_penetration_mm < 1.0);  // paper 001
  CHECK(l.rendered_stiffness_N_per_m >= 3.0 * s.rendered_stiffness_N_per_m);
  // The referee's depth agrees with the scene's geometry (the test's own measure, from the sensed
  // tool against the block's known top), within the encoders' resolution at the tool.
  CHECK(s.max_true_penetration_mm == Approx(1e3 * spring.max_penetration).margin(0.15));
  CHECK(l.max_true_penetration_mm == Approx(1e3 * lqr.max_penetration).margin(0.15));
}

TEST_CASE("tau: a soft object stays with the spring (no LQR wall)", "[chai3d][tau]") {
  const Result soft = pushIntoBlock(cTauDevice::C_TAU_WALL_AUTO, 500.0);  // below the 3000 N/m threshold
  CHECK(soft.contacts >= 1);
  CHECK_FALSE(soft.lqr_engaged);
}

TEST_CASE("tau: a servo tick allocates nothing", "[chai3d][tau]") {
  auto device = cTauDevice::create(tauSelection(cTauDevice::C_TAU_WALL_LQR));
  device->setLockStep(true);
  REQUIRE(device->open());
  cVector3d p;
  for (int i = 0; i < 10; ++i) device->setForce(cVector3d(0, 0, 1.0));
  uhaptics::tools::AllocationScope scope;
  for (int i = 0; i < 1000; ++i) {
    device->getPosition(p);
    device->setForce(cVector3d(0.0, 0.0, i % 200 < 100 ? 5.0 : 0.0));  // in and out of contact
  }
  CHECK(scope.count() == 0);
}

// ---- the LQR wall in unchanged scenes: engagement rule, curved and concave surfaces, friction,
// ---- chatter, and the renderer figures that report them

namespace {

double figure(const cTauDevicePtr& device, const char* name) {
  const uhaptics::SessionStatsSnapshot stats = device->getSessionStats();
  const uhaptics::RendererFigure* f = stats.figure(name);
  REQUIRE(f != nullptr);
  return f->value;
}

bool reporting() { return std::getenv("UHAPTICS_TEST_REPORT") != nullptr; }

// The scripted hand on a closed path (workspace radii): a stiff spring, 8 N at most.
uhaptics::DeviceSelection handPath(std::vector<uhaptics::Vec3> waypoints, double lap_time) {
  uhaptics::DeviceSelection s;
  s.device = "tau";
  s.hand.waypoints = std::move(waypoints);
  s.hand.lap_time = lap_time;
  s.hand.stiffness = 1500.0;
  s.hand.damping = 20.0;
  s.hand.max_force = 8.0;
  return s;
}

double degrees(double radians) { return radians * 180.0 / M_PI; }

struct Slide {
  double max_depth = 0.0;         // m, tool below the sphere's surface while the wall owns the contact
  double worst_normal = 0.0;      // deg, wall's normal vs the sphere's, while the application feels contact
  double arc_min = 1e9, arc_max = -1e9;  // deg, polar angle of the tool over the sphere while held
  double engagements = 0.0, overloads = 0.0;
};

// A rigid sphere of radius 0.6 r (15 mm) whose top is 0.2 r below the workspace centre. The hand
// comes down left of the top, presses and slides across to the right, lifts and returns through
// the air: one slide per 4 s lap. shape: cShapeSphere (CHAI3D's potential field: the tool's centre
// meets the surface) in a world in device units; else a 64 x 64 mesh sphere (the finger proxy: the
// tool's radius meets it) in a world of radius 1 as CHAI3D's examples map it.
Slide slideOverSphere(bool shape) {
  auto device = cTauDevice::create(handPath({uhaptics::Vec3(-0.6, 0, 0.2), uhaptics::Vec3(-0.6, 0, -0.35),
                                             uhaptics::Vec3(0.6, 0, -0.35), uhaptics::Vec3(0.6, 0, 0.2)},
                                            4.0));
  device->setLockStep(true);
  const double r = device->getSpecifications().m_workspaceRadius;
  ToolScene scene(device, kToolRadius, shape ? 0.0 : 1.0);
  const double scale = scene.scale();
  scene.tool->setRadius(kToolRadius * scale);
  const double radius = 0.6 * r;
  const cVector3d centre(0.0, 0.0, -0.8 * r);  // device frame [m]
  if (shape) {
    auto* sphere = new cShapeSphere(radius * scale);
    scene.world.addChild(sphere);
    sphere->setLocalPos(centre * scale);
    sphere->createEffectSurface();
    sphere->m_material->setStiffness(6000.0 / scale);
  } else {
    auto* sphere = new cMesh();
    scene.world.addChild(sphere);
    cCreateSphere(sphere, radius * scale, 64, 64);
    sphere->setLocalPos(centre * scale);
    sphere->createAABBCollisionDetector(kToolRadius * scale);
    sphere->m_material->setStiffness(6000.0 / scale);
  }
  const double surface = radius + (shape ? 0.0 : kToolRadius);  // where the tool's centre meets it
  REQUIRE(scene.tool->start());
  Slide result;
  for (int i = 0; i < 4000; ++i) {
    scene.tick();
    REQUIRE(device->getLastFault() == uhaptics::Fault::kNone);
    if (!device->isLqrWallEngaged()) continue;
    cVector3d position, point, normal;
    device->getPosition(position);
    const cVector3d radial = position - centre;
    result.max_depth = std::max(result.max_depth, surface - radial.length());
    if (device->getLqrPenetration() > 0.0) {
      const double arc = degrees(std::atan2(radial.x(), radial.z()));
      result.arc_min = std::min(result.arc_min, arc);
      result.arc_max = std::max(result.arc_max, arc);
    }
    if (scene.tool->getDeviceGlobalForce().length() > 0.05 && device->getContactSurface(point, normal))
      result.worst_normal = std::max(result.worst_normal, degrees(std::acos(cClamp(normal.dot(cNormalize(radial)), -1.0, 1.0))));
  }
  result.engagements = figure(device, "lqr_engagements");
  result.overloads = figure(device, "lqr_overloads");
  return result;
}

}  // namespace

TEST_CASE("tau: the LQR wall follows a rigid sphere the tool slides over", "[chai3d][tau]") {
  for (const bool shape : {true, false}) {
    const Slide slide = slideOverSphere(shape);
    INFO((shape ? "cShapeSphere" : "mesh sphere") << ": depth " << slide.max_depth * 1e3 << " mm, normal off by "
                                                   << slide.worst_normal << " deg, held over " << slide.arc_min
                                                   << ".." << slide.arc_max << " deg");
    if (reporting()) WARN((shape ? "cShapeSphere" : "mesh sphere") << ": depth " << slide.max_depth * 1e3
                          << " mm, normal off by " << slide.worst_normal << " deg, held over " << slide.arc_min << ".."
                          << slide.arc_max << " deg, engagements " << slide.engagements);
    CHECK(slide.engagements == 1.0);  // one slide, one contact
    CHECK(slide.overloads == 0.0);
    // Held while the tool slid through more than 30 deg of the sphere (a plane latched at the first
    // touch would leave the sphere's surface by R (1 - cos 30 deg) = 2 mm over that arc).
    CHECK(slide.arc_max - slide.arc_min > 30.0);
    CHECK(slide.max_depth < 1e-3);  // paper 001's bound
    // The plane turns with the surface: within 10 deg of the sphere's normal (its filters lag by
    // about a degree at this speed; the rest is the tool bouncing off the wall, during which the
    // plane waits; measured 4-8 deg).
    CHECK(slide.worst_normal < 10.0);
  }
}

namespace {

// A groove along y: two rigid faces at +-45 deg meeting 0.2 r below the workspace centre (a mesh,
// the finger proxy; world in device units). The hand of the 12 N block push presses the tool into
// the crease twice. Depth: the most the tool's sphere overlaps either face.
struct Groove {
  double max_depth = 0.0;  // m
  bool engaged = false;
  double overloads = 0.0;
};
Groove pushIntoGroove(cTauDevice::cWallMode mode) {
  auto device = cTauDevice::create(tauSelection(mode));
  device->setLockStep(true);
  const double r = device->getSpecifications().m_workspaceRadius;
  ToolScene scene(device, kToolRadius);
  auto* groove = new cMesh();
  scene.world.addChild(groove);
  const double crease = -0.2 * r;
  const double a = r;  // half width
  groove->newTriangle(cVector3d(-a, -2 * a, crease + a), cVector3d(0, -2 * a, crease), cVector3d(0, 2 * a, crease));
  groove->newTriangle(cVector3d(-a, -2 * a, crease + a), cVector3d(0, 2 * a, crease), cVector3d(-a, 2 * a, crease + a));
  groove->newTriangle(cVector3d(0, -2 * a, crease), cVector3d(a, -2 * a, crease + a), cVector3d(a, 2 * a, crease + a));
  groove->newTriangle(cVector3d(0, -2 * a, crease), cVector3d(a, 2 * a, crease + a), cVector3d(0, 2 * a, crease));
  groove->computeAllNormals();
  groove->createAABBCollisionDetector(kToolRadius);
  groove->m_material->setStiffness(6000.0);
  const cVector3d left = cNormalize(cVector3d(1, 0, 1)), right = cNormalize(cVector3d(-1, 0, 1));
  const cVector3d bottom(0, 0, crease);
  REQUIRE(scene.tool->start());
  Groove result;
  for (int i = 0; i < 4000; ++i) {
    scene.tick();
    REQUIRE(device->getLastFault() == uhaptics::Fault::kNone);
    const cVector3d p = scene.tool->getDeviceGlobalPos() - bottom;
    result.max_depth = std::max(result.max_depth, kToolRadius - std::max(p.dot(left), p.dot(right)));
    result.engaged = result.engaged || device->isLqrWallEngaged();
  }
  result.overloads = figure(device, "lqr_overloads");
  return result;
}

}  // namespace

TEST_CASE("tau: a concave groove pushed into is held on both faces", "[chai3d][tau]") {
  const Groove lqr = pushIntoGroove(cTauDevice::C_TAU_WALL_AUTO);
  const Groove spring = pushIntoGroove(cTauDevice::C_TAU_WALL_SPRING);
  if (reporting()) WARN("12 N into a 90 deg groove: depth LQR " << lqr.max_depth * 1e3 << " mm, spring " << spring.max_depth * 1e3 << " mm");
  CHECK(lqr.engaged);
  CHECK(lqr.overloads == 0.0);
  // One plane through the crease normal to the faces' combined force holds the push; the faces'
  // forces across it are the application's spring, so the tool stays in the crease.
  CHECK(lqr.max_depth < 1e-3);  // paper 001's bound
  CHECK_FALSE(spring.engaged);
  CHECK(spring.max_depth > 2.0 * lqr.max_depth);
}

TEST_CASE("tau: friction does not tilt the wall's normal", "[chai3d][tau]") {
  // A rigid block with Coulomb friction (static 0.5, dynamic 0.4: a slipping finger proxy tilts its
  // force 22 deg off the normal, a stuck one up to 27 deg). The hand comes straight down, presses
  // with up to 8 N, slides 25 mm across, lifts and returns through the air.
  auto device = cTauDevice::create(handPath({uhaptics::Vec3(-0.5, 0, 0.0), uhaptics::Vec3(-0.5, 0, -0.5),
                                             uhaptics::Vec3(0.5, 0, -0.5), uhaptics::Vec3(0.5, 0, 0.0)},
                                            4.0));
  device->setLockStep(true);
  ToolScene scene(device, kToolRadius);
  cMesh* block = scene.addBlock(0.2, 6000.0);
  block->m_material->setStaticFriction(0.5);
  block->m_material->setDynamicFriction(0.4);
  block->m_material->setUseHapticFriction(true);
  REQUIRE(scene.tool->start());
  double worst_normal = 0.0, worst_force = 0.0, x_min = 1e9, x_max = -1e9;
  for (int i = 0; i < 4000; ++i) {
    scene.tick();
    REQUIRE(device->getLastFault() == uhaptics::Fault::kNone);
    const cVector3d force = scene.tool->getDeviceGlobalForce();
    cVector3d point, normal;
    if (!device->isLqrWallEngaged() || force.z() < 0.05 || !device->getContactSurface(point, normal)) continue;
    worst_normal = std::max(worst_normal, degrees(std::acos(cClamp(normal.z(), -1.0, 1.0))));
    worst_force = std::max(worst_force, degrees(std::acos(cClamp(force.z() / force.length(), -1.0, 1.0))));
    x_min = std::min(x_min, point.x());
    x_max = std::max(x_max, point.x());
  }
  if (reporting()) WARN("friction: wall's normal off by " << worst_normal << " deg, the application's force by up to "
                        << worst_force << " deg, over " << (x_max - x_min) * 1e3 << " mm of sliding");
  CHECK(figure(device, "lqr_engagements") == 1.0);
  CHECK(x_max - x_min > 20e-3);           // it slid
  CHECK(worst_force > degrees(std::atan(0.4)));  // and friction tilted the application's force
  // The wall's normal: within 8 deg of the face's, a third of the sliding friction's 22 deg (the
  // force's tilt along the proxy's path is removed; what is left is the slow average of the proxy's
  // jitter across the path; measured 3.4 deg, and 27 deg with the force used as it comes).
  CHECK(worst_normal < 8.0);
}

TEST_CASE("tau: a steady push is one engagement, held throughout, within the torque limits",
          "[chai3d][tau]") {
  // The block push's hand, but its anchor keeps going down for 4 s: one steady 12 N push.
  auto selection = tauSelection(cTauDevice::C_TAU_WALL_AUTO);
  selection.hand.lap_time = 8.0;
  auto device = cTauDevice::create(selection);
  device->setLockStep(true);
  ToolScene scene(device, kToolRadius);
  scene.addBlock(0.2, 6000.0);
  REQUIRE(scene.tool->start());
  int engaged_ticks = 0, flips = 0;
  bool was = false;
  for (int i = 0; i < 4000; ++i) {
    scene.tick();
    REQUIRE(device->getLastFault() == uhaptics::Fault::kNone);
    const bool engaged = device->isLqrWallEngaged();
    flips += engaged != was;
    was = engaged;
    engaged_ticks += engaged;
  }
  const double held = figure(device, "lqr_held_ticks");
  if (reporting()) WARN("steady push: engaged " << engaged_ticks << " ticks, held " << held << ", saturated "
                        << figure(device, "lqr_saturated_ticks") << ", deepest " << figure(device, "max_penetration_mm") << " mm");
  CHECK(flips == 1);  // engaged once, never released
  CHECK(figure(device, "lqr_engagements") == 1.0);
  CHECK(figure(device, "lqr_releases") == 0.0);
  CHECK(engaged_ticks > 1500);  // from the first touch (about 2 s in) to the end
  // Held most of it: the rest are ticks where the tool, pushed back onto the plane, is just above it.
  CHECK(held > 0.8 * engaged_ticks);
  CHECK(figure(device, "max_penetration_mm") < 1.0);
  CHECK(figure(device, "lqr_saturated_ticks") == 0.0);  // at the centre the wall stays within the limits
}

TEST_CASE("tau: a surface below the stiffness threshold stays with the spring and is reported soft",
          "[chai3d][tau]") {
  // 04-shapes' spheres: 0.4 of the device's maxLinearStiffness, 2400 N/m at the device.
  auto device = cTauDevice::create(tauSelection(cTauDevice::C_TAU_WALL_AUTO));
  device->setLockStep(true);
  ToolScene scene(device, kToolRadius, 1.0);  // as 04-shapes maps it: workspace radius 1
  scene.tool->setRadius(kToolRadius * scene.scale());
  scene.addBlock(0.2, 0.4 * device->getSpecifications().m_maxLinearStiffness);
  REQUIRE(scene.tool->start());
  for (int i = 0; i < 4000; ++i) {
    scene.tick();
    REQUIRE_FALSE(device->isLqrWallEngaged());
  }
  const double measured = figure(device, "soft_stiffness_max_N_per_m");
  if (reporting()) WARN("2400 N/m surface: measured " << measured << " N/m, soft contacts " << figure(device, "soft_surface_contacts"));
  CHECK(figure(device, "lqr_engagements") == 0.0);
  CHECK(figure(device, "soft_surface_contacts") == 2.0);  // two pushes
  CHECK(figure(device, "spring_contact_ticks") > 1000.0);
  // The probe measures the application's 2400 N/m (the tool's spring is in series with nothing
  // else; 10 %: the depth is summed over 0.2 mm in 1 ms steps).
  CHECK(measured == Approx(2400.0).epsilon(0.1));
}

TEST_CASE("tau: the renderer figures are declared by name", "[chai3d][tau]") {
  auto device = cTauDevice::create(tauSelection(cTauDevice::C_TAU_WALL_AUTO));
  const uhaptics::SessionStatsSnapshot stats = device->getSessionStats();
  using Kind = uhaptics::RendererFigure::Kind;
  for (const char* name : {"lqr_engagements", "lqr_held_ticks", "spring_contact_ticks", "soft_surface_contacts",
                           "lqr_releases", "lqr_saturated_ticks", "lqr_overloads"}) {
    INFO(name);
    REQUIRE(stats.figure(name) != nullptr);
    CHECK(stats.figure(name)->kind == Kind::kCount);
  }
  for (const char* name : {"max_entry_depth_mm", "max_penetration_mm", "soft_stiffness_max_N_per_m"}) {
    INFO(name);
    REQUIRE(stats.figure(name) != nullptr);
    CHECK(stats.figure(name)->kind == Kind::kMaximum);
  }
}
