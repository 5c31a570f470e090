#include <catch2/catch.hpp>
#include <random>

#include "rhi_fixtures.hpp"
#include "uhaptics/core/finite_difference.hpp"
#include "uhaptics/experiments/rhi_experiments.hpp"

using namespace uhaptics;

namespace {
using rhi_test::randomConfiguration;
using rhi_test::rhi4;
}  // namespace

TEST_CASE("RHI Jacobian is eq. 20 of paper 003 and the derivative of the forward kinematics") {
  static_assert(kIsKinematicModel<Rhi4Model> && kHasJacobianDerivative<Rhi4Model> && kHasMassMatrix<Rhi4Model>);
  const auto& m = rhi4();
  const double d1 = 0.254, d2 = 0.141, d3 = 0.21, d4 = 0.181;
  std::mt19937 rng(3);
  for (int trial = 0; trial < 50; ++trial) {
    const Vec<4> q = randomConfiguration(rng);
    Mat<2, 4> J, eq20;
    m.jacobian(q, J);
    const double q23 = q(1) + q(2), q24 = q(1) + q(3);
    eq20 << -d1 * std::sin(q(0)), d2 * std::cos(q(1)) - d3 * std::sin(q23) + d4 * std::cos(q24), -d3 * std::sin(q23),
        d4 * std::cos(q24), d1 * std::cos(q(0)), d2 * std::sin(q(1)) + d3 * std::cos(q23) + d4 * std::sin(q24),
        d3 * std::cos(q23), d4 * std::sin(q24);
    CHECK((J - eq20).cwiseAbs().maxCoeff() < 1e-15);  // same formula, round-off only
    const auto fd = centralDifferenceJacobian(
        [&](const Vec<4>& qq) {
          Vec2 x;
          m.forward(qq, x);
          return x;
        },
        q);
    // Central differences with h ~ 6e-6 on O(0.5 m) terms: truncation ~ h^2 ~ 4e-11, round-off ~ 1e-11.
    CHECK((J - fd).cwiseAbs().maxCoeff() < 1e-8);
    for (int k = 0; k < 4; ++k) {
      Mat<2, 4> dJ;
      m.jacobianDerivative(q, k, dJ);
      Vec<4> qp = q, qm = q;
      const double h = 1e-6;
      qp(k) += h;
      qm(k) -= h;
      Mat<2, 4> Jp, Jm;
      m.jacobian(qp, Jp);
      m.jacobian(qm, Jm);
      CHECK((dJ - (Jp - Jm) / (2 * h)).cwiseAbs().maxCoeff() < 1e-8);
    }
  }
}

TEST_CASE("RHI mass matrix is symmetric positive definite and its Coriolis terms follow from it") {
  const auto& m = rhi4();
  std::mt19937 rng(5);
  std::normal_distribution<double> n01;
  for (int trial = 0; trial < 20; ++trial) {
    const Vec<4> q = randomConfiguration(rng);
    const Vec<4> qd(n01(rng), n01(rng), n01(rng), n01(rng));
    Mat<4, 4> M;
    m.massMatrix(q, M);
    CHECK((M - M.transpose()).cwiseAbs().maxCoeff() < 1e-15);
    CHECK(M.llt().info() == Eigen::Success);
    // Lagrange: c = Mdot qd - 1/2 d(qd^T M qd)/dq, with Mdot and the gradient by central differences.
    Vec<4> c;
    m.velocityProductTorque(q, qd, c);
    const double h = 1e-6;
    Mat<4, 4> Mp, Mm;
    m.massMatrix(q + h * qd, Mp);
    m.massMatrix(q - h * qd, Mm);
    Vec<4> expected = (Mp - Mm) / (2 * h) * qd;
    for (int k = 0; k < 4; ++k) {
      Vec<4> qp = q, qm = q;
      qp(k) += h;
      qm(k) -= h;
      m.massMatrix(qp, Mp);
      m.massMatrix(qm, Mm);
      expected(k) -= 0.5 * qd.dot((Mp - Mm) / (2 * h) * qd);
    }
    CHECK((c - expected).cwiseAbs().maxCoeff() < 1e-7);  // FD of O(1e-2) quantities, h = 1e-6
  }
}

TEST_CASE("the frictionless simulated RHI conserves kinetic energy") {
  auto p = rhi4().parameters();
  p.viscous_friction.setZero();
  p.coulomb_friction.setZero();
  SimulatedPlanarLinkage<4> sim(Rhi4Model(p), 1e-5);
  sim.reset(Vec<4>(0.3, -0.2, 0.5, 1.0), Vec<4>(1.0, -0.5, 0.8, 0.3));
  auto energy = [&] {
    Mat<4, 4> M;
    sim.model().massMatrix(sim.position(), M);
    return 0.5 * sim.velocity().dot(M * sim.velocity());
  };
  const double e0 = energy();
  for (int k = 0; k < 200; ++k) sim.step(Vec<4>::Zero(), 1e-3);
  // Semi-implicit Euler drifts O(h) per unit time: 1e-5 s steps over 0.2 s keep it below 1 %.
  CHECK(std::abs(energy() / e0 - 1.0) < 0.01);
}

TEST_CASE("the simulated RHI saturates torques and brakes with friction") {
  SimulatedPlanarLinkage<4> sim(rhi4());
  sim.reset(Vec<4>::Zero());
  sim.step(Vec<4>(100.0, -100.0, 5.0, -5.0), 1e-3);
  CHECK(sim.appliedTorque().isApprox(Vec<4>(3.0, -3.0, 1.0, -1.0)));
  CHECK(sim.step(Vec<4>::Constant(std::nan("")), 1e-3) == Fault::kNonFiniteInput);
  CHECK(sim.position().allFinite());
  sim.reset(Vec<4>::Zero(), Vec<4>(2.0, 2.0, 2.0, 2.0));
  for (int k = 0; k < 3000; ++k) sim.step(Vec<4>::Zero(), 1e-3);
  CHECK(sim.velocity().norm() < 1e-3);
}

TEST_CASE("planar3 example device matches the paper's FME at q0") {
  const auto& m = test::planar3Model();
  Mat<2, 3> J;
  m.jacobian(m.homeJoints(), J);
  Mat2 fme;
  REQUIRE(fme::weightedFme(J, fme::inverseSquaredLimits(m.effortLimits()), fme));
  const auto s = fme::ellipsoidScales(fme, 1.0);
  // Paper: M_free = diag(0.2 x 2.6, 5 x 5.8): eigenvalues of M_hat at q0 printed to 2 digits.
  CHECK(s.major == Approx(5.8).margin(0.05));
  CHECK(s.minor == Approx(2.6).margin(0.05));
}

TEST_CASE("malformed RHI parameter files are rejected with a clear error") {
  const std::string dir = test::paramsDir();
  CHECK_THROWS_WITH(Rhi4Model::load(dir + "/planar3.json", "rhi4"), Catch::Contains("expected 'rhi4'"));
  CHECK_THROWS_WITH(Planar3Model::load(dir + "/rhi4.json", "rhi4"), Catch::Contains("joints"));
  CHECK_THROWS_AS(Rhi4Model::load(dir + "/missing.json", "rhi4"), Error);
  auto p = rhi4().parameters();
  p.link_length(2) = -0.1;
  CHECK_THROWS_WITH(Rhi4Model(p), Catch::Contains("link_length[2]"));
  p = rhi4().parameters();
  p.coupling.col(3).setZero();
  CHECK_THROWS_WITH(Rhi4Model(p), Catch::Contains("joint 3"));
  p = rhi4().parameters();
  p.torque_limit(0) = 0.0;
  CHECK_THROWS_AS(Rhi4Model(p), Error);
  p = rhi4().parameters();
  p.joint_limits.lower(1) = p.joint_limits.upper(1);
  CHECK_THROWS_WITH(Rhi4Model(p), Catch::Contains("joint limits"));
  p = rhi4().parameters();
  p.joint_limits.lower(0) = 0.1;  // home q1 = 0 below it
  CHECK_THROWS_WITH(Rhi4Model(p), Catch::Contains("home"));
}

TEST_CASE("RHI joint limits: parallelogram internal angles in [30, 150] deg, motors within 90 deg of home") {
  const auto& l = rhi4().jointLimits();
  REQUIRE(l.any());
  CHECK(l.distance(rhi4().homeJoints()) == Approx(M_PI / 3));  // both internal angles at 90 deg, 60 deg from a stop
  // Links 1 and 2 folded flat (q1 - q2 + 90 deg = 0) or links 3 and 4 stretched straight are outside.
  CHECK_FALSE(l.contains(Vec<4>(0.0, M_PI / 2, 0.0, 0.0)));
  CHECK_FALSE(l.contains(Vec<4>(0.0, 0.0, 0.0, M_PI / 2)));
  // The planar3 example has no stops.
  CHECK_FALSE(test::planar3Model().jointLimits().any());
}
