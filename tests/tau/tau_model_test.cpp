#include "uhaptics/models/tau_model.hpp"

#include <catch2/catch.hpp>
#include <cmath>

#include "device_models.hpp"
#include "uhaptics/core/decompositions.hpp"
#include "uhaptics/core/finite_difference.hpp"
#include "uhaptics/core/kinematic_model.hpp"
#include "uhaptics/models/param_file.hpp"

using namespace uhaptics;

namespace {

// The dynamics tests' state: the joints of an off-centre pose (every coordinate moved) and a joint
// velocity with every joint moving.
Vec6 offCentreJoints() {
  Vec6 pose;
  pose << -0.015, 0.01, -0.01, 0.05, 0.08, -0.1;
  Vec6 q;
  REQUIRE(test::tauModel().inverse(pose, q) == Fault::kNone);
  return q;
}
Vec6 jointVelocity() {
  Vec6 qd;
  qd << 0.7, -1.1, 0.4, 0.9, -0.3, 1.2;
  return qd;
}
}  // namespace

TEST_CASE("TAU model satisfies the kinematic-model interface") { STATIC_REQUIRE(kIsKinematicModel<TauModel>); }

TEST_CASE("TAU workspace: 50 mm cube x +-10 deg reachable, FK inverts IK, Jacobian well conditioned") {
  const TauModel& m = test::tauModel();
  TauData data(m);
  const double h = m.workspaceHalfSide(), a = m.workspaceHalfAngle();
  double worst_cond = 0.0, worst_roundtrip = 0.0;
  int worst_iterations = 0, poses = 0;
  // 5^3 positions x 3^3 orientations (corners included): 3375 poses.
  for (int ix = 0; ix < 5; ++ix)
    for (int iy = 0; iy < 5; ++iy)
      for (int iz = 0; iz < 5; ++iz)
        for (int ia = 0; ia < 27; ++ia) {
          Vec6 pose;
          pose << -h + ix * h / 2, -h + iy * h / 2, -h + iz * h / 2, (ia % 3 - 1) * a, ((ia / 3) % 3 - 1) * a,
              (ia / 9 - 1) * a;
          Vec6 q;
          REQUIRE(m.inverse(pose, q) == Fault::kNone);
          data.pose = m.homePose();  // cold start: the hardest case for Newton
          REQUIRE(m.forward(q, data) == Fault::kNone);
          worst_roundtrip = std::max(worst_roundtrip, (data.pose - pose).cwiseAbs().maxCoeff());
          worst_iterations = std::max(worst_iterations, data.fk_iterations);
          worst_cond = std::max(worst_cond, TauModel::scaledConditionNumber(data.J, m.characteristicLength()));
          ++poses;
        }
  INFO("poses " << poses << " worst condition " << worst_cond << " worst FK iterations " << worst_iterations);
  // Newton's quadratic convergence reaches 1e-12 m; 1e-10 allows the pose-level error amplification.
  CHECK(worst_roundtrip < 1e-10);
  // Bounded condition number = free of singularities with margin (measured worst 11.8; the bound
  // leaves ~1.7x for a lab's parameter tweaks without hiding a real degradation).
  CHECK(worst_cond < 20.0);
  CHECK(worst_iterations <= 8);
  WARN("TAU workspace scan: worst scaled condition number " << worst_cond << ", worst cold-start FK iterations "
                                                            << worst_iterations);
}

TEST_CASE("TAU statics: a 15 N + 3 sigma push anywhere on the wall needs well under the 2 N m saturation") {
  // Paper 001's scenario 1 pushes with F_c <= 15 N plus N(0, 0.5) N noise at the tool, wall z = 0,
  // x, y in [-25, 25] mm. Holding it statically takes tau = g(q) - J^T F. The LQR wall also needs
  // headroom for the transient of the first impact, so we require at most half the saturation.
  const TauModel& m = test::tauModel();
  TauData data(m);
  const double h = m.workspaceHalfSide();
  const double push = 15.0 + 3.0 * 0.5;
  double worst = 0.0;
  for (int ix = 0; ix <= 10; ++ix)
    for (int iy = 0; iy <= 10; ++iy) {
      Vec6 pose = m.homePose();
      pose(0) = -h + ix * h / 5;
      pose(1) = -h + iy * h / 5;
      Vec6 q;
      REQUIRE(m.inverse(pose, q) == Fault::kNone);
      data.pose = pose;
      REQUIRE(m.forward(q, data) == Fault::kNone);
      m.computeGravity(q, data);
      const Vec6 tau = data.gravity - data.J.topRows<3>().transpose() * Vec3(0.0, 0.0, -push);
      worst = std::max(worst, tau.cwiseQuotient(m.effortLimits()).cwiseAbs().maxCoeff());
    }
  WARN("16.5 N push on the wall: worst static joint torque " << 100.0 * worst << " % of the saturation");
  CHECK(worst < 0.5);
}

TEST_CASE("TAU kinematics: the branch test by the signs of dg/dq agrees with the inverse's round trip") {
  // Every leg flipped to its other branch in turn, at poses over the workspace: the sign test
  // (RusLegKinematics) and the round trip through inverse() (TauKinematics' default) must agree on
  // every closure solution, the own branches and each flipped one.
  const TauModel& m = test::tauModel();
  const auto& kin = dynamic_cast<const RusLegKinematics&>(m.kinematics());
  std::array<RusLegKinematics::Leg, 6> legs;
  for (int i = 0; i < 6; ++i) legs[i] = kin.leg(i);
  for (double x : {-0.02, 0.0, 0.02})
    for (double y : {-0.02, 0.02})
      for (double a : {-0.1, 0.0, 0.1}) {
        Vec6 pose = m.homePose();
        pose(0) += x;
        pose(1) += y;
        pose(2) += 0.5 * y;
        pose(3) += a;
        pose(4) -= 0.5 * a;
        pose(5) += 0.3 * a;
        for (int flip = -1; flip < 6; ++flip) {
          std::array<RusLegKinematics::Leg, 6> flipped = legs;
          if (flip >= 0) flipped[flip].branch = -flipped[flip].branch;
          Vec6 q;
          REQUIRE(RusLegKinematics(flipped).inverse(pose, q) == Fault::kNone);
          Vec6 g;
          Mat6 dg_dpose, dg_dq;
          kin.constraints(pose, q, g, dg_dpose, dg_dq);
          REQUIRE(g.cwiseAbs().maxCoeff() < 1e-12);  // a closure solution
          const bool by_signs = kin.onAssembledBranches(pose, q, dg_dq, 1e-9);
          const bool by_round_trip = kin.TauKinematics::onAssembledBranches(pose, q, dg_dq, 1e-9);
          CHECK(by_signs == by_round_trip);
          CHECK(by_signs == (flip < 0));
        }
      }
}

TEST_CASE("TAU Jacobian matches finite differences of the forward kinematics") {
  const TauModel& m = test::tauModel();
  Vec6 pose;
  pose << 0.01, -0.02, 0.015, 0.1, -0.05, 0.12;
  Vec6 q;
  REQUIRE(m.inverse(pose, q) == Fault::kNone);
  Mat6 J;
  m.jacobian(q, J);
  const Mat6 Jfd = centralDifferenceJacobian(
      [&](const Vec6& qq) {
        Vec6 x;
        m.forward(qq, x);
        return x;
      },
      q);
  // Central differences with h ~ 6e-6 rad: O(h^2) truncation, FK solved to 1e-12 m.
  CHECK((J - Jfd).norm() < 1e-6 * J.norm());
}

TEST_CASE("TAU dynamics: symmetric positive mass matrix, gravity = gradient of potential energy") {
  const TauModel& m = test::tauModel();
  const Vec6 q = offCentreJoints();
  TauData d(m);
  REQUIRE(m.forward(q, d) == Fault::kNone);
  REQUIRE(m.computeDynamicsTerms(q, Vec6::Zero(), d) == Fault::kNone);
  CHECK((d.M - d.M.transpose()).norm() < 1e-14);
  // Kinetic energy of every lumped mass: the rotors (their inertia about the axes, link and rod
  // halves included) plus each platform point's m |S_c J qd|^2 / 2.
  Mat6 M = m.jointInertia().asDiagonal();
  for (const auto& pm : m.platformMasses()) {
    const Mat<3, 6> T = PoseRotation(d.pose).pointJacobian(pm.body_point) * d.J;
    M += pm.mass * T.transpose() * T;
  }
  CHECK((d.M - M).norm() < 1e-12 * M.norm());
  Vec6 mass_eigen;
  REQUIRE(symmetricEigen(d.M, mass_eigen));
  CHECK(mass_eigen.minCoeff() > 0.0);
  // Potential energy V(q) = -sum m g.x over every lumped mass; the gravity torque is dV/dq.
  auto potential = [&](const Vec6& qq) {
    TauData dd(m);
    m.forward(qq, dd);
    const PoseRotation rot(dd.pose);
    double V = 0.0;
    for (const auto& pm : m.platformMasses()) V -= pm.mass * m.gravityVector().dot(dd.pose.head<3>() + rot.R * pm.body_point);
    for (int i = 0; i < 6; ++i) {
      Vec3 p, dp;
      m.kinematics().linkPoint(i, qq(i), m.linkComRadius()(i), p, dp);
      V -= m.linkMass()(i) * m.gravityVector().dot(p);
      m.kinematics().linkPoint(i, qq(i), m.kinematics().linkLength(i), p, dp);
      V -= 0.5 * m.rodMass()(i) * m.gravityVector().dot(p);
    }
    return V;
  };
  Vec6 dV;
  for (int i = 0; i < 6; ++i) {
    const double h = 1e-6;
    Vec6 qp = q, qm = q;
    qp(i) += h;
    qm(i) -= h;
    dV(i) = (potential(qp) - potential(qm)) / (2 * h);
  }
  // Central difference of V (~0.1 J) with h = 1e-6: error ~1e-9 N m.
  CHECK((d.gravity - dV).norm() < 1e-7);
}

TEST_CASE("TAU dynamics: velocity term = mass-weighted velocity-product accelerations of the platform points") {
  // Reference: each platform point's acceleration along q(t) = q + t qd (qdd = 0), a five-point
  // second difference of its position on forward kinematics solved to 1e-12 m, over joint steps of
  // 5 mrad at either speed (h = 5e-3 s / scale): truncation ~h^4, rounding ~1e-12 m / h^2. The
  // model's closed form agrees to 2.3e-8 at both speeds; with 10 mrad steps, to 3.7e-7 (16 times
  // more: the reference's h^4 truncation is what is measured). 2e-7 leaves a factor 9.
  const TauModel& m = test::tauModel();
  const Vec6 q = offCentreJoints();
  const Vec6 qd = jointVelocity();
  for (const double scale : {1.0, 5.0}) {
    const Vec6 v = scale * qd;
    TauData d(m);
    REQUIRE(m.forward(q, d) == Fault::kNone);
    REQUIRE(m.computeDynamicsTerms(q, v, d) == Fault::kNone);
    const double h = 5e-3 / scale;
    Vec6 expected = Vec6::Zero();
    for (const auto& pm : m.platformMasses()) {
      auto point = [&](double t) {
        TauData dd(m);
        REQUIRE(m.forward(q + t * v, dd) == Fault::kNone);
        return Vec3(dd.pose.head<3>() + PoseRotation(dd.pose).R * pm.body_point);
      };
      const Vec3 accel = (-point(2 * h) + 16.0 * point(h) - 30.0 * point(0) + 16.0 * point(-h) - point(-2 * h)) /
                         (12.0 * h * h);
      expected += pm.mass * (PoseRotation(d.pose).pointJacobian(pm.body_point) * d.J).transpose() * accel;
    }
    CAPTURE(scale, d.bias.transpose(), expected.transpose());
    CHECK((d.bias - expected).norm() < 2e-7 * expected.norm());
  }
}

TEST_CASE("TAU kinematics: the closure's acceleration in closed form = its second difference along the motion") {
  // Along the line (X + t X', q + t q') (X'' = 0, q'' = 0), a five-point second difference of
  // closure() over 1 mrad joint steps: truncation ~h^4 g^(6) ~ 1e-12 of g'', rounding 1e-16 m /
  // h^2. TauKinematics' own default (a three-point difference, truncation ~1e-6 relative) is the
  // same quantity for any geometry; both against the closed form of RusLegKinematics.
  const TauModel& m = test::tauModel();
  const TauKinematics& kin = m.kinematics();
  const Vec6 q = offCentreJoints();
  const Vec6 qd = jointVelocity();
  TauData d(m);
  REQUIRE(m.forward(q, d) == Fault::kNone);
  const Vec6 Xd = d.J * qd;
  Vec6 exact, default_difference;
  kin.closureAcceleration(d.pose, q, Xd, qd, exact);
  kin.TauKinematics::closureAcceleration(d.pose, q, Xd, qd, default_difference);
  const double h = 1e-3 / qd.cwiseAbs().maxCoeff();
  auto g = [&](double t) {
    Vec6 r;
    kin.closure(d.pose + t * Xd, q + t * qd, r);
    return r;
  };
  const Vec6 five_point = (-g(2 * h) + 16.0 * g(h) - 30.0 * g(0) + 16.0 * g(-h) - g(-2 * h)) / (12.0 * h * h);
  CAPTURE(exact.transpose(), five_point.transpose(), default_difference.transpose());
  CHECK((exact - five_point).norm() < 1e-8 * exact.norm());
  CHECK((exact - default_difference).norm() < 1e-5 * exact.norm());
}

TEST_CASE("TAU parameter file errors are reported with the key") {
  CHECK_THROWS_WITH(TauModel::fromParams(ParamFile::parse(R"({"device":"tau","format_version":1})", "inline")),
                    Catch::Contains("legs/leg1/base"));
  CHECK_THROWS_WITH(TauModel::fromParams(ParamFile::parse(R"({"device":"exo","format_version":1})", "inline")),
                    Catch::Contains("tau"));
}
