#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <utility>

#include "renderer_fixtures.hpp"
#include "uhaptics/backends/simulated_tau.hpp"
#include "uhaptics/core/eigenvalues.hpp"
#include "uhaptics/renderers/lqr_wall_renderer.hpp"
#include "uhaptics/renderers/spring_wall_renderer.hpp"
#include "uhaptics/renderers/tau_wall_design.hpp"
#include "uhaptics/tools/alloc_probe.hpp"

using namespace uhaptics;

namespace {
const LqrWallDesign& design() { return test::tauHomeDesign(); }
SurfaceContact wallAt(const Vec6& pose) {
  SurfaceContact c;
  c.active = true;
  c.point = Vec3(pose(0), pose(1), 0.0);
  c.normal = Vec3::UnitZ();
  return c;
}
}  // namespace

TEST_CASE("LQR wall design: fastest pole ~2480 rad/s, verified DARE, stable observer") {
  const LqrWallGains& g = test::tauHomeGains();
  const LqrWallDesignReport& report = design().report;
  // Paper: "around 2480 rad/s"; our weights are tuned for our assumed plant to keep it there.
  CHECK(report.fastest_pole_rad_s == Approx(2480.0).epsilon(0.05));
  CHECK(report.dare_residual < 1e-10);
  CHECK(g.Kc.allFinite());
  CHECK((g.Ki * g.Ki_inverse - Mat6::Identity()).norm() < 1e-9);
  // The observer must be stable: the estimation error dynamics (I - L C) A have |z| < 1.
  Mat<6, 18> C = Mat<6, 18>::Zero();
  C.block<6, 6>(0, 6).setIdentity();
  const Mat<18, 18> E = (Mat<18, 18>::Identity() - g.observer.gain * C) * g.observer.A;
  CHECK(spectralRadius(E) < 1.0);
}

TEST_CASE("Gain-only redesign at a contact point: same controller as a full design, observer kept") {
  const LqrWallGains& centre = test::tauHomeGains();
  Mat<6, 18> C = Mat<6, 18>::Zero();
  C.block<6, 6>(0, 6).setIdentity();
  const double h = test::tauModel().workspaceHalfSide();
  for (const auto& [x, y] : {std::pair{-h, -h}, std::pair{-h, h}, std::pair{h, -h}, std::pair{h, h}}) {
    Vec6 corner = test::tauModel().homePose();
    corner(0) = x;
    corner(1) = y;
    const LqrWallGains full = designLqrWall(test::tauModel(), corner).gains;
    const LqrWallGains quick = redesignLqrWallGains(test::tauModel(), corner, design()).gains;
    // Same DARE, same inputs: identical up to the solver's rounding.
    CHECK((quick.Kc - full.Kc).norm() < 1e-9 * full.Kc.norm());
    CHECK((quick.Ki - full.Ki).norm() < 1e-9 * full.Ki.norm());
    CHECK(quick.observer.gain == centre.observer.gain);
    CHECK(quick.observer.joints == centre.observer.joints);
    // Why the observer may stay: the centre's filter is still stable on the corner's plant, i.e.
    // the estimation error e+ = (I - L C) A_corner e contracts (A_corner from the corner's design).
    const Mat<18, 18> E = (Mat<18, 18>::Identity() - centre.observer.gain * C) * full.observer.A;
    CHECK(spectralRadius(E) < 1.0);
  }
}

TEST_CASE("LQR wall design rejects unreachable operating points with a clear error") {
  Vec6 far = test::tauModel().homePose();
  far(2) = 0.5;
  CHECK_THROWS_WITH(designLqrWall(test::tauModel(), far), Catch::Contains("outside the reachable workspace"));
  LqrWallWeights w;
  w.torque = 0.0;
  CHECK_THROWS_AS(designLqrWall(test::tauModel(), test::tauModel().homePose(), w), Error);
  CHECK_THROWS_WITH(redesignLqrWallGains(test::tauModel(), far, design()), Catch::Contains("outside the reachable workspace"));
}

TEST_CASE("Bad input to the wall renderers: a Fault and a zero torque, never NaN") {
  LqrWallRenderer lqr(test::tauModel(), test::tauHomeGains());
  SpringWallRenderer spring(test::tauModel());
  const Vec6 q = test::tauModel().homeJoints();
  const SurfaceContact contact = wallAt(test::tauModel().homePose());
  SECTION("non-finite joint reading") {
    Vec6 bad = q;
    bad(3) = std::numeric_limits<double>::quiet_NaN();
    CHECK(lqr.tick(bad, contact).fault == Fault::kNonFiniteInput);
    CHECK(lqr.command().torque.isZero());
    CHECK(spring.tick(bad, contact).fault == Fault::kNonFiniteInput);
    CHECK(spring.command().torque.isZero());
  }
  SECTION("non-finite or non-unit surface normal") {
    SurfaceContact c = contact;
    c.normal = Vec3(0, 0, 2);
    CHECK(lqr.tick(q, c).fault == Fault::kNonFiniteInput);
    CHECK(lqr.command().torque.isZero());
    c.normal = Vec3(0, std::nan(""), 1);
    CHECK(spring.tick(q, c).fault == Fault::kNonFiniteInput);
    CHECK(spring.command().torque.isZero());
  }
  SECTION("joints with no forward-kinematics solution") {
    // Alternate links +-86 deg: the legs' rod spheres do not meet near any pose Newton can reach.
    Vec6 impossible;
    impossible << 1.5, -1.5, 1.5, -1.5, 1.5, -1.5;
    CHECK(lqr.tick(impossible, contact).fault != Fault::kNone);
    CHECK(lqr.command().torque.isZero());
  }
  SECTION("unreachable reference: surface far below the workspace") {
    SurfaceContact c = contact;
    c.point = Vec3(0, 0, 0.3);  // the tool is 0.3 m 'inside': the projected reference is unreachable
    CHECK(lqr.tick(q, c).fault == Fault::kOutOfRange);
    CHECK(lqr.command().torque.isZero());
    // A valid tick afterwards recovers.
    CHECK(lqr.tick(q, contact).fault == Fault::kNone);
    CHECK(lqr.command().torque.allFinite());
  }
}

TEST_CASE("Wall renderer ticks are allocation-free and free-space ticks skip the contact work") {
  SimulatedTauOptions so;
  so.tool_rotational_damping = 0.01;  // the handle's, as cTauDevice simulates it
  SimulatedTau sim(test::tauModel(), so);
  LqrWallRenderer lqr(test::tauModel(), test::tauHomeGains());
  SpringWallRenderer spring(test::tauModel());
  TauData device(test::tauModel());
  SurfaceContact contact = wallAt(test::tauModel().homePose());
  Vec6 tau = Vec6::Zero();
  // Warm up (first-use static initialization is allowed to allocate).
  tau = lqr.tick(sim.encoderReading(), contact).torque;
  spring.tick(sim.encoderReading(), contact);
  tools::AllocationScope scope;
  for (int k = 0; k < 200; ++k) {
    test::tauModel().forward(sim.encoderReading(), device);
    contact.point = Vec3(device.pose(0), device.pose(1), 0.0);
    tau = lqr.tick(sim.encoderReading(), contact, &device.pose).torque;
    spring.tick(sim.encoderReading(), contact, &device.pose);
    sim.step(tau, Vec3(0, 0, k > 50 ? -10.0 : 0.0));
  }
  CHECK(scope.count() == 0);
  CHECK(lqr.command().in_contact);
  // Free space: inactive contact gives exactly the gravity compensation (no LQR term).
  SurfaceContact none;
  LqrWallRenderer fresh(test::tauModel(), test::tauHomeGains());
  const WallCommand& cmd = fresh.tick(sim.encoderReading(), none);
  TauData d(test::tauModel());
  test::tauModel().forward(sim.encoderReading(), d);
  test::tauModel().computeGravity(sim.encoderReading(), d);
  CHECK(!cmd.in_contact);
  CHECK((cmd.torque - d.gravity).norm() < 1e-12);
}

namespace {
// Largest penetration under an 8 N step push along -normal into a wall through the start point.
double stepPenetration(const Vec3& normal) {
  SimulatedTauOptions so;
  so.quantize = false;
  SimulatedTau sim(test::tauModel(), so);
  LqrWallRenderer lqr(test::tauModel(), test::tauHomeGains());
  SurfaceContact c;
  c.active = true;
  c.normal = normal;
  c.point = sim.pose().head<3>();
  double worst = 0.0;
  for (int k = 0; k < 1500; ++k) {
    const WallCommand& cmd = lqr.tick(sim.encoderReading(), c);
    if (cmd.fault != Fault::kNone) return 1.0;
    sim.step(cmd.torque, k > 200 ? Vec3(-8.0 * c.normal) : Vec3::Zero());
    worst = std::max(worst, -c.normal.dot(sim.pose().head<3>() - c.point));
  }
  return worst;
}
}  // namespace

TEST_CASE("Any surface: a tilted wall is held along its own normal") {
  const double flat = stepPenetration(Vec3::UnitZ());
  const double tilted = stepPenetration(Vec3(std::sin(M_PI / 6), 0, std::cos(M_PI / 6)));
  WARN("8 N step, sliding-mode LQR wall: flat " << flat * 1e3 << " mm, tilted 30 deg " << tilted * 1e3 << " mm");
  // A step (not a ramp) in the sliding mode: first impact within 2 mm on both (measured 0.56 and
  // 1.32 mm: the device is stiffer along z than along x, condition number ~14 at the centre).
  CHECK(flat < 2e-3);
  CHECK(tilted < 2e-3);
}

namespace {
// A push along -normal into a wall tilted 30 deg (the handle's rotational damping as cTauDevice
// simulates it). Over the ticks whose command saturates: the largest sine of the angle between
// the wall's force (J^-T of the torque beyond gravity compensation) and the normal line.
struct SaturatedPush {
  bool fault = false;
  int saturated_ticks = 0;
  double worst_sine = 0.0;
  double depth = 0.0;  // deepest below the wall [m]
  double side = 0.0;   // farthest along it from the start [m]
};
SaturatedPush saturatedPush(bool keep_direction, double push) {
  SimulatedTauOptions so;
  so.tool_rotational_damping = 0.01;
  SimulatedTau sim(test::tauModel(), so);
  LqrWallRenderer::Options options;
  options.keep_direction = keep_direction;
  LqrWallRenderer lqr(test::tauModel(), test::tauHomeGains(), options);
  SurfaceContact c;
  c.active = true;
  c.normal = Vec3(std::sin(M_PI / 6), 0, std::cos(M_PI / 6));
  c.point = sim.pose().head<3>();
  TauData data(test::tauModel());
  SaturatedPush result;
  for (int k = 0; k < 1000; ++k) {
    const WallCommand& cmd = lqr.tick(sim.encoderReading(), c);
    if (cmd.fault != Fault::kNone) {
      result.fault = true;
      break;
    }
    const Vec3 offset = sim.pose().head<3>() - c.point;
    result.depth = std::max(result.depth, -c.normal.dot(offset));
    result.side = std::max(result.side, (offset - c.normal.dot(offset) * c.normal).norm());
    if (cmd.saturated && cmd.in_contact) {
      data.pose = sim.pose();
      REQUIRE(test::tauModel().forward(sim.encoderReading(), data) == Fault::kNone);
      test::tauModel().computeGravity(sim.encoderReading(), data);
      const Vec3 force = data.J.transpose().partialPivLu().solve(cmd.torque - data.gravity).head<3>();
      ++result.saturated_ticks;
      result.worst_sine = std::max(result.worst_sine, force.normalized().cross(c.normal).norm());
    }
    sim.step(cmd.torque, k > 100 ? Vec3(-push * c.normal) : Vec3::Zero());
  }
  return result;
}
}  // namespace

TEST_CASE("keep_direction: a saturating push into a tilted wall is held along the normal") {
  // 14 N: within what the device can push along this normal, but the LQR's command (dominated by
  // the encoders' quantization at its gains) saturates joints now and then.
  const SaturatedPush kept = saturatedPush(true, 14.0);
  const SaturatedPush clamped = saturatedPush(false, 14.0);
  WARN("14 N into a 30 deg wall, kept / per-joint: saturated ticks " << kept.saturated_ticks << " / "
       << clamped.saturated_ticks << ", worst sine " << kept.worst_sine << " / " << clamped.worst_sine << ", depth "
       << kept.depth * 1e3 << " / " << clamped.depth * 1e3 << " mm, sideways " << kept.side * 1e3 << " / "
       << clamped.side * 1e3 << " mm, fault " << kept.fault << " / " << clamped.fault);
  REQUIRE(kept.saturated_ticks > 0);
  CHECK_FALSE(kept.fault);
  CHECK(kept.worst_sine < 1e-6);  // on the normal line, to rounding
  CHECK(kept.depth < 1e-3);       // paper 001's bound
  // Per-joint clamping bends the force off the normal and the tool slides away along the wall.
  CHECK((clamped.fault || clamped.worst_sine > std::sin(10.0 * M_PI / 180)));
}
