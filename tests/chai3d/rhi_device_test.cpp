// cRedundantPlanarDevice on the simulated backend with a stock CHAI3D world and cToolCursor (no
// graphics): specification, J^T F through the tool, the null space leaving the tool force alone,
// options from code and from the config file, the statistics file, no allocation per tick.
#include <catch2/catch.hpp>
#include <Eigen/Cholesky>
#include "uhaptics/core/decompositions.hpp"  // the fixed-size SVDs, compiled once
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>

#include "chai3d.h"
#include "params.hpp"
#include "tool_scene.hpp"
#include "uhaptics/chai3d/CRedundantPlanarDevice.hpp"
#include "uhaptics/tools/alloc_probe.hpp"

using namespace chai3d;
using Model = cRedundantPlanarDevice::Model;

namespace {

uhaptics::DeviceSelection rhiSelection() {
  uhaptics::DeviceSelection s;
  s.device = "rhi";
  s.hand.waypoints = {uhaptics::Vec3(0, 0, 0.2), uhaptics::Vec3(0, 0, -0.6)};  // palpate downwards
  s.hand.lap_time = 2.0;
  return s;
}

// The null-space controller's options under their option names ("options/rhi/<name>").
std::map<std::string, double> named(const cRedundantPlanarDevice::Controller::Options& o) {
  return {{"mu", o.mu},
          {"beta", o.beta},
          {"damping", o.damping},
          {"eps1", o.transition.enter_stiff_below},
          {"eps2", o.transition.leave_stiff_at},
          {"rho", o.transition.rho},
          {"mode", static_cast<double>(o.mode)}};
}

// The null-space envelope's ramp r(t) (FmeControllerOptions::null_space_ramp_time).
double rampAt(double a_time, double a_rampTime) {
  const double u = a_time / a_rampTime;
  return u < 1.0 ? 0.5 * (1.0 - std::cos(M_PI * u)) : 1.0;
}

}  // namespace

TEST_CASE("rhi: specification complete and consistent with the model", "[chai3d][rhi]") {
  auto device = cRedundantPlanarDevice::create(rhiSelection());
  const cHapticDeviceInfo info = device->getSpecifications();
  const Model& model = device->getModel();
  CHECK(info.m_model == C_HAPTIC_DEVICE_CUSTOM);
  CHECK_THAT(info.m_modelName, Catch::Contains("redundant") && Catch::Contains("sim"));
  CHECK(info.m_manufacturerName == "uhaptics");
  CHECK(info.m_maxLinearStiffness == 1000.0);  // paper 003's stiff environment
  CHECK(info.m_maxLinearDamping > 0.0);
  CHECK(info.m_workspaceRadius == 0.1);
  CHECK(info.m_workspaceRadius < 0.25 * model.reach());  // far from the reach boundary
  CHECK(info.m_sensedPosition);
  CHECK(info.m_actuatedPosition);
  CHECK_FALSE(info.m_sensedRotation);
  CHECK_FALSE(info.m_actuatedRotation);
  CHECK(info.m_maxAngularTorque == 0.0);
  CHECK(info.m_maxAngularStiffness == 0.0);
  CHECK(info.m_maxGripperForce == 0.0);
  CHECK_FALSE(info.m_sensedGripper);

  // The advertised force is available in every direction at home: J^T (F_max u) within every
  // joint's limit for all u, and it is not needlessly conservative: some direction needs at least
  // half of some joint's limit (the ellipse inscribed in the 4-D torque box touches it at most
  // a factor sqrt(4) = 2 inside).
  Model::Jacobian J;
  model.jacobian(model.homeJoints(), J);
  double worst_use = 0.0;
  for (int k = 0; k < 360; ++k) {
    const double a = k * M_PI / 180.0;
    const Model::JointVector tau = J.transpose() * (info.m_maxLinearForce * uhaptics::Vec2(std::cos(a), std::sin(a)));
    const double use = (tau.cwiseAbs().array() / model.effortLimits().array()).maxCoeff();
    CHECK(use <= 1.0 + 1e-12);
    worst_use = std::max(worst_use, use);
  }
  CHECK(worst_use >= 0.5);
  CHECK(info.m_maxLinearForce > 1.0);  // newtons from 1-3 N m joints on 0.14-0.25 m links

  double q[C_MAX_DOF];
  CHECK_FALSE(device->getJointAnglesRad(q));  // closed: not ready
  REQUIRE(device->open());
  REQUIRE(device->getJointAnglesRad(q));
  for (int i = 0; i < 4; ++i) CHECK(q[i] == model.homeJoints()(i));
  CHECK(q[4] == 0.0);  // only four joints
  cVector3d p;
  REQUIRE(device->getPosition(p));
  CHECK(p.length() == 0.0);  // the origin is the home end-effector position
  cMatrix3d r;
  REQUIRE(device->getRotation(r));
  cMatrix3d identity = cIdentity3d();
  CHECK(r.equals(identity));  // planar: no orientation
  CHECK(device->close());
}

TEST_CASE("rhi: the tool's force is rendered as J^T F and the null space leaves it unchanged",
          "[chai3d][rhi]") {
  auto device = cRedundantPlanarDevice::create(rhiSelection());
  device->setLockStep(true);
  ToolScene scene(device, 0.005);
  scene.addBlock(0.3, device->getSpecifications().m_maxLinearStiffness);  // top face 3 cm below home
  REQUIRE(scene.tool->start());
  const Model& model = device->getModel();
  int contact_ticks = 0, unscaled_ticks = 0;
  double largest_null = 0.0, worst_leak = 0.0, kinematic_leak = 0.0;
  for (int i = 0; i < 4000; ++i) {
    const Model::JointVector q = device->getJointPositions();  // the state this tick's controller sees
    scene.tick();
    const auto status = device->getNullSpaceStatus();
    REQUIRE(status.fault == uhaptics::Fault::kNone);
    const cVector3d f = scene.tool->getDeviceLocalForce();
    CHECK(f.x() == 0.0);  // the block's top face is horizontal: the proxy pushes in the y-z plane
    const uhaptics::Vec2 F(f.y(), -f.z());  // device y-z plane -> task plane
    Model::Jacobian J;
    model.jacobian(q, J);
    // Primary task: exactly J^T (alpha F), alpha <= 1 the uniform saturation scale. 1e-12 relative:
    // the same four dot products, in another order at most.
    CHECK((status.tau_primary - J.transpose() * (status.alpha * F)).norm() <= 1e-12 * (1.0 + status.tau_primary.norm()));
    CHECK(status.alpha <= 1.0);
    if (F.norm() < 0.5) continue;  // well in contact only (0.5 N: 0.5 mm into the 1000 N/m block)
    ++contact_ticks;
    if (status.alpha == 1.0) ++unscaled_ticks;
    CHECK(F.y() < 0.0);  // the block pushes up (task -y is device +z)
    // The null-space torque's force contribution: with the dynamically consistent inverse
    // J# = M^-1 J^T (J M^-1 J^T)^-1 it is J#^T tau_N, the force that gives the same end-effector
    // acceleration (J M^-1 tau_N). It must vanish: the tool feels exactly the primary task.
    Model::MassMatrix M;
    model.massMatrix(q, M);
    const Eigen::Matrix<double, 4, 2> MinvJt = Eigen::LLT<Model::MassMatrix>(M).solve(J.transpose());
    const Eigen::Matrix<double, 2, 4> JsharpT = (J * MinvJt).ldlt().solve(MinvJt.transpose());
    // Measured as a fraction of the force a joint torque of the same size can produce at most
    // (|J#^T|_2 |tau|): dimensionless, 1 for the worst direction.
    const double reach = Eigen::JacobiSVD<Eigen::Matrix<double, 2, 4>>(JsharpT).singularValues()(0);
    const auto leakFraction = [&](const Model::JointVector& tau) {
      return (JsharpT * tau).norm() / (reach * std::max(1e-9, tau.norm()));
    };
    largest_null = std::max(largest_null, status.tau_null.norm());
    if (status.tau_null.norm() < 1e-6) continue;
    worst_leak = std::max(worst_leak, leakFraction(status.tau_null));
    // Control: the same torque projected with the kinematic (Moore-Penrose) null space instead,
    // which ignores the dynamics: this one does push the tool, so the measure can tell them apart.
    const Model::JointVector kinematic =
        status.tau_null - J.transpose() * (J * J.transpose()).ldlt().solve(J * status.tau_null);
    kinematic_leak = std::max(kinematic_leak, leakFraction(kinematic));
  }
  INFO("contact ticks " << contact_ticks << ", unscaled " << unscaled_ticks << ", largest |tau_N| "
                        << largest_null << " N m, leak fraction " << worst_leak << " (kinematic projection "
                        << kinematic_leak << ")");
  CHECK(contact_ticks > 500);
  CHECK(unscaled_ticks > contact_ticks / 2);  // mostly rendered unscaled: the check is about F itself
  CHECK(largest_null > 1e-2);  // the null space was really active (else the leak check proves nothing)
  // Round-off: the projector and this check each solve with M (condition <= 94 along this path) and
  // J M^-1 J^T (<= 12), so errors of order eps k(M) k(Lambda) ~ 2.5e-13 are expected (4.3e-12 was
  // measured). 1e-9 leaves a margin of 200; the kinematic projection leaks ~0.9.
  CHECK(worst_leak < 1e-9);
  CHECK(kinematic_leak > 0.1);
  CHECK(device->getSessionStats().contacts >= 1);
  scene.tool->stop();
}

TEST_CASE("rhi: a stock cToolCursor palpates a cShapeBox (potential field) and is held on top",
          "[chai3d][rhi]") {
  auto device = cRedundantPlanarDevice::create(rhiSelection());
  device->setLockStep(true);
  const double r = device->getSpecifications().m_workspaceRadius;
  const double tool_radius = 0.005;
  ToolScene scene(device, tool_radius);
  cShapeBox* box = new cShapeBox(4 * r, 4 * r, 2 * r);
  scene.world.addChild(box);
  box->setLocalPos(0.0, 0.0, -1.3 * r);  // top face at z = -0.3 r = -3 cm
  const double stiffness = device->getSpecifications().m_maxLinearStiffness;
  box->m_material->setStiffness(stiffness);
  box->createEffectSurface();
  REQUIRE(scene.tool->start());
  const double surface = -0.3 * r + tool_radius;  // tool centre height when touching
  double deepest = 0.0, peak = 0.0;
  for (int i = 0; i < 4000; ++i) {
    scene.tick();
    REQUIRE(device->getLastFault() == uhaptics::Fault::kNone);
    const double depth = surface - scene.tool->getDeviceGlobalPos().z();
    deepest = std::max(deepest, depth);
    peak = std::max(peak, scene.tool->getDeviceGlobalForce().z());
  }
  const auto stats = device->getSessionStats();
  INFO("deepest " << deepest * 1e3 << " mm, peak force " << peak << " N, contacts " << stats.contacts);
  CHECK(stats.contacts >= 1);
  CHECK(peak > 1.0);  // a real push, not ripple
  // The hand pushes with at most 8 N; held by the 1000 N/m surface the tool sinks at most
  // 8 mm, plus overshoot from the approach speed (the hand's path is 8 cm in one second): 15 mm.
  CHECK(deepest > 0.0);
  CHECK(deepest < 0.015);
  CHECK(stats.peak_force == Approx(peak).epsilon(1e-9));
  scene.tool->stop();
}

TEST_CASE("rhi: in an empty scene the null-space torque ramps up from zero and stays within its bound",
          "[chai3d][rhi]") {
  // An unchanged CHAI3D application with nothing to touch: the default scripted hand (the drop-in
  // examples') moves the device, the cursor renders no force. From home the FME gradient asks for
  // 5.4 N m (beta = 20); without the envelope the first tick commanded the full 3 N m.
  uhaptics::DeviceSelection selection;
  selection.device = "rhi";
  auto device = cRedundantPlanarDevice::create(selection);
  const auto options = device->getNullSpaceOptions();
  const double bound = options.max_null_space_torque, ramp = options.null_space_ramp_time;
  CHECK(bound == cRedundantPlanarDevice::kDefaultMaxNullSpaceTorque);
  CHECK(ramp == cRedundantPlanarDevice::kDefaultNullSpaceRampTime);
  CHECK(bound <= 0.5 * device->getModel().effortLimits().minCoeff());  // well below every actuator's limit
  device->setLockStep(true);
  ToolScene scene(device, 0.005);
  REQUIRE(scene.tool->start());
  const double dt = device->getServoPeriod();
  Model::JointVector previous = Model::JointVector::Zero();
  double first_steps = 0.0;  // largest per-tick change of tau_N over the first 100 ticks
  for (int i = 0; i < 5000; ++i) {  // 5 s: more than a lap of the hand (4 s)
    scene.tick();
    REQUIRE(device->getLastFault() == uhaptics::Fault::kNone);
    REQUIRE(scene.tool->getDeviceLocalForce().length() == 0.0);  // empty: the primary task J^T F is zero
    const auto status = device->getNullSpaceStatus();
    if (i == 0) CHECK(status.tau_null.isZero());
    // Never above the ramped bound r(t) B (1e-12: round-off of the scale B / |tau_N,cmd|).
    CHECK(status.tau_null.norm() <= rampAt(i * dt, ramp) * bound + 1e-12);
    if (i < 100) first_steps = std::max(first_steps, (status.tau_null - previous).norm());
    previous = status.tau_null;
  }
  scene.tool->stop();
  const auto stats = device->getSessionStats();
  // The bound on what the actuators are told: tau = J^T F + tau_N with F = 0 here, so every
  // |tau_i| <= |tau_N|_2 <= B. And the bound is what holds it: the start-up command is 11 B.
  CHECK(stats.peak_output <= bound * (1.0 + 1e-12));
  CHECK(stats.peak_output > 0.9 * bound);
  CHECK(stats.figure("max_null_space_torque_Nm")->value == Approx(bound).epsilon(1e-9));
  // Smooth start: the half cosine rises by at most pi dt / (2 T) = 0.63 % of B per tick; the
  // command's own turning while the arm starts from rest adds little (0.62 % measured). 1 % of B.
  INFO("largest step over the first 100 ticks " << first_steps << " N m");
  CHECK(first_steps <= 0.01 * bound);
  // Nothing to press: the desired ellipsoid stays the free one, the force is never scaled.
  CHECK(stats.figure("free_to_stiff")->value == 0.0);
  CHECK(stats.figure("stiff_to_free")->value == 0.0);
  CHECK(stats.figure("stiff_ticks")->value == 0.0);
  CHECK(stats.figure("max_force_scale_reduction")->value == 0.0);
  // A reopened device starts its ramp again from zero.
  REQUIRE(device->open());
  device->setForce(cVector3d(0.0, 0.0, 0.0));
  CHECK(device->getNullSpaceStatus().tau_null.isZero());
  device->setForce(cVector3d(0.0, 0.0, 0.0));
  CHECK(device->getNullSpaceStatus().tau_null.norm() > 0.0);
  CHECK(device->getNullSpaceStatus().tau_null.norm() <= rampAt(dt, ramp) * bound + 1e-12);
  CHECK(device->close());
}

TEST_CASE("rhi: a stock cToolCursor pressing a stiff object switches to the stiff ellipsoid and back smoothly",
          "[chai3d][rhi]") {
  auto device = cRedundantPlanarDevice::create(rhiSelection());  // the hand palpates down and back, 2 s a lap
  device->setLockStep(true);
  const double stiffness = device->getSpecifications().m_maxLinearStiffness;  // paper 003's 1000 N/m
  ToolScene scene(device, 0.005);
  SECTION("a mesh (finger proxy)") { scene.addBlock(0.3, stiffness); }
  SECTION("a cShapeBox (potential field)") {
    const double r = device->getSpecifications().m_workspaceRadius;
    cShapeBox* box = new cShapeBox(4 * r, 4 * r, 2 * r);
    scene.world.addChild(box);
    box->setLocalPos(0.0, 0.0, -1.3 * r);  // top face 3 cm below home, as the mesh's
    box->m_material->setStiffness(stiffness);
    box->createEffectSurface();
  }
  REQUIRE(scene.tool->start());
  const double bound = device->getNullSpaceOptions().max_null_space_torque;
  int to_stiff = 0, to_free = 0, stiff_ticks = 0;
  bool heading_stiff = false;
  double largest_reduction = 0.0, largest_null = 0.0, transition_step = 0.0;
  Model::JointVector previous = Model::JointVector::Zero();
  uhaptics::FmeControllerStatus<4, 2> status;
  for (int i = 0; i < 4000; ++i) {  // two presses and releases
    scene.tick();
    REQUIRE(device->getLastFault() == uhaptics::Fault::kNone);
    status = device->getNullSpaceStatus();
    // The primary task keeps its authority, the null space stays within its bound: every actuator
    // gets at most its share of J^T (alpha F) plus B (1e-12: round-off of the scale).
    CHECK(status.tau_null.norm() <= bound * (1.0 + 1e-12));
    const double output = (status.tau_primary + status.tau_null).cwiseAbs().maxCoeff();
    CHECK(output <= status.tau_primary.cwiseAbs().maxCoeff() + bound * (1.0 + 1e-12));
    const bool stiff_target = status.omega_target == 0.0;
    const bool switched = stiff_target != heading_stiff;
    if (switched) ++(stiff_target ? to_stiff : to_free);
    heading_stiff = stiff_target;
    if (status.omega < 1.0) ++stiff_ticks;
    const double step = (status.tau_null - previous).norm();
    if (switched || stiff_target || status.omega < 1.0) transition_step = std::max(transition_step, step);
    previous = status.tau_null;
    largest_reduction = std::max(largest_reduction, 1.0 - status.alpha);
    largest_null = std::max(largest_null, status.tau_null.norm());
  }
  scene.tool->stop();
  const auto stats = device->getSessionStats();
  INFO("to stiff " << to_stiff << ", to free " << to_free << ", stiff ticks " << stiff_ticks
                   << ", largest null-space step in a switch or blend " << transition_step << " N m");
  // The figures the drop-in scenes read say what the controller did.
  CHECK(stats.figure("free_to_stiff")->value == to_stiff);
  CHECK(stats.figure("stiff_to_free")->value == to_free);
  CHECK(stats.figure("stiff_ticks")->value == stiff_ticks);
  CHECK(stats.figure("max_force_scale_reduction")->value == largest_reduction);
  CHECK(stats.figure("max_null_space_torque_Nm")->value == largest_null);
  // The press drove the observer below eps1 (stiff ellipsoid), the release back above eps2, and
  // the blend back to the free ellipsoid completed.
  CHECK(to_stiff >= 1);
  CHECK(stiff_ticks > 0);
  CHECK(to_free >= 1);
  CHECK(status.omega == 1.0);
  // No discontinuity across the switches and blends: at most 0.8 B per tick (0.27 N m on the
  // mesh, 0.20 N m on the shape measured: the command's own rate where the FME and joint-limit
  // terms cross while the arm swings along its self-motion). A reversal of the bounded torque
  // would be 2 B; the release step when the stiff axis followed the vanishing proxy force was
  // 1.4 B, 6.4 N m without the bound.
  CHECK(transition_step <= 0.8 * bound);
}

namespace {
// Two presses into a stiff mesh (paper 003's 1000 N/m) by the same scripted hand, lock-step (the
// same user input every run), with the null-space mode given; the referee's figures from the truth.
// The hand presses with up to 5 N, about what the arm can push back with there: with the free-motion
// ellipsoid alone its actuators saturate through most of the press.
uhaptics::RefereeReport pressAndRelease(double a_mode) {
  uhaptics::DeviceSelection selection = rhiSelection();
  selection.hand.stiffness = 400.0;
  selection.hand.max_force = 5.0;
  selection.options["mode"] = a_mode;
  auto device = cRedundantPlanarDevice::create(selection);
  device->setLockStep(true);
  ToolScene scene(device, 0.005);
  scene.addBlock(0.3, device->getSpecifications().m_maxLinearStiffness);
  REQUIRE(scene.tool->start());
  for (int i = 0; i < 4000; ++i) {
    scene.tick();
    REQUIRE(device->getLastFault() == uhaptics::Fault::kNone);
  }
  scene.tool->stop();
  const uhaptics::SessionStatsSnapshot stats = device->getSessionStats();
  REQUIRE(stats.has_referee);
  return stats.referee;
}
}  // namespace

TEST_CASE("rhi: the referee: the stiff ellipsoid renders the press closer to what the scene asks than the "
          "free one alone", "[chai3d][rhi][referee]") {
  const uhaptics::RefereeReport switching = pressAndRelease(0.0);  // paper 003's switching
  const uhaptics::RefereeReport free_only = pressAndRelease(1.0);  // the free-motion ellipsoid only
  INFO("switching: force error " << switching.force_error_rms_N << " N, saturated " << switching.saturated_share
                                 << ", depth " << switching.max_true_penetration_mm << " mm, stiffness "
                                 << switching.rendered_stiffness_N_per_m << " N/m; free only: "
                                 << free_only.force_error_rms_N << " N, " << free_only.saturated_share << ", "
                                 << free_only.max_true_penetration_mm << " mm, "
                                 << free_only.rendered_stiffness_N_per_m << " N/m");
  // Measured: force error 5.5 N against 7.8 N, saturated 8 % of the contact ticks against 54 %. Neither
  // holds the press (the hand sinks the tool some 23 mm into the 1000 N/m block either way: the arm
  // there gives at most about 4.8 N along the press).
  CHECK(switching.contacts >= 1);
  CHECK(switching.contacts == free_only.contacts);
  CHECK(switching.force_error_rms_N < 0.85 * free_only.force_error_rms_N);
  CHECK(switching.saturated_share < 0.5 * free_only.saturated_share);
}

TEST_CASE("rhi: null-space options from CHAI3D code, the selection and the config file", "[chai3d][rhi]") {
  SECTION("the paper's defaults, changed through the device class, invalid ones refused") {
    auto device = cRedundantPlanarDevice::create(rhiSelection());
    auto options = device->getNullSpaceOptions();
    const std::map<std::string, double> paper = {{"mu", 5.0},   {"beta", 20.0}, {"damping", 0.1}, {"eps1", 0.7},
                                                 {"eps2", 0.95}, {"rho", 0.003}, {"mode", 0.0}};  // paper 003
    CHECK(named(options) == paper);
    options.mu = -1.0;
    CHECK_FALSE(device->setNullSpaceOptions(options));
    options.mu = 5.0;
    options.transition.enter_stiff_below = 0.99;  // eps1 > eps2: no hysteresis
    CHECK_FALSE(device->setNullSpaceOptions(options));
    CHECK(device->getNullSpaceOptions().mu == 5.0);  // refused: the previous options stay
    CHECK(device->getNullSpaceOptions().transition.enter_stiff_below == 0.7);
    options.transition.enter_stiff_below = 0.7;
    options.mode = uhaptics::FmeEllipsoidMode::kStiff;
    CHECK(device->setNullSpaceOptions(options));
    device->setLockStep(true);
    REQUIRE(device->open());
    device->setForce(cVector3d(0.0, 0.0, 1.0));
    CHECK(device->getNullSpaceStatus().omega == 0.0);  // always the stiff-contact ellipsoid
    options.mode = uhaptics::FmeEllipsoidMode::kFree;
    CHECK(device->setNullSpaceOptions(options));  // while running
    device->setForce(cVector3d(0.0, 0.0, 1.0));
    CHECK(device->getNullSpaceStatus().omega == 1.0);
  }
  // mode 2 = always the stiff-contact ellipsoid (FmeEllipsoidMode::kStiff).
  const std::map<std::string, double> chosen = {{"mu", 3.0},  {"beta", 10.0}, {"damping", 0.2}, {"eps1", 0.6},
                                                {"eps2", 0.9}, {"rho", 0.01},  {"mode", 2.0}};
  SECTION("DeviceSelection options set in code") {
    auto selection = rhiSelection();
    selection.options = chosen;
    CHECK(named(cRedundantPlanarDevice::create(selection)->getNullSpaceOptions()) == chosen);
    selection.options = {{"eps1", 0.96}};  // above the default eps2
    CHECK_THROWS_WITH(cRedundantPlanarDevice::create(selection), Catch::Contains("options/rhi"));
    selection.options = {{"mu", 0.0}};
    CHECK_THROWS_WITH(cRedundantPlanarDevice::create(selection), Catch::Contains("rhi/mu"));
  }
  SECTION("options/rhi/<name> in the UHAPTICS_CONFIG file") {
    const std::string path = "uhaptics-rhi-options-test.json";
    {
      std::ofstream out(path);
      out << R"({"device": "chai3d-selection", "format_version": 1, "selection": {"device": "rhi"}, "options": {"rhi": {)";
      const char* separator = "";
      for (const auto& [name, value] : chosen) {
        out << separator << '"' << name << "\": " << value;
        separator = ", ";
      }
      out << "}}}";
    }
    const auto selection = uhaptics::readDeviceSelection({"rhi"}, {"sim"}, [&](const char* name) -> const char* {
      return std::string(name) == "UHAPTICS_CONFIG" ? path.c_str() : nullptr;
    });
    std::remove(path.c_str());
    CHECK(named(cRedundantPlanarDevice::create(selection)->getNullSpaceOptions()) == chosen);
  }
}

TEST_CASE("rhi: the statistics file on close shows the contact and the rendered force", "[chai3d][rhi]") {
  auto selection = rhiSelection();
  selection.stats_path = "uhaptics-rhi-stats-test.json";
  std::remove(selection.stats_path.c_str());
  auto device = cRedundantPlanarDevice::create(selection);
  device->setLockStep(true);
  {
    ToolScene scene(device, 0.005);
    scene.addBlock(0.3, device->getSpecifications().m_maxLinearStiffness);
    REQUIRE(scene.tool->start());
    for (int i = 0; i < 2000; ++i) scene.tick();
    scene.tool->stop();  // closes the device: the file is written now
  }
  const std::string json = uhaptics::test::readFile(selection.stats_path);
  std::remove(selection.stats_path.c_str());
  CHECK_THAT(json, Catch::Contains("\"device\": \"rhi\"") && Catch::Contains("\"ticks\": 2000") &&
                       Catch::Contains("FME null space"));
  const auto stats = device->getSessionStats();
  CHECK(stats.contacts >= 1);
  CHECK(stats.peak_force > 1.0);
  CHECK(stats.peak_output > 0.0);
  CHECK(stats.faults == 0);
}

TEST_CASE("rhi: a servo tick allocates nothing", "[chai3d][rhi]") {
  auto device = cRedundantPlanarDevice::create(rhiSelection());
  device->setLockStep(true);
  REQUIRE(device->open());
  cVector3d p;
  uhaptics::tools::AllocationScope scope;
  for (int i = 0; i < 1000; ++i) {
    device->getPosition(p);
    device->setForce(cVector3d(0.0, 0.3, i % 2 == 0 ? 2.0 : 0.0));  // contact and free-motion paths
  }
  CHECK(scope.count() == 0);
}
