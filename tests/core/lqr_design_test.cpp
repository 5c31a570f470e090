#include "uhaptics/core/lqr_design.hpp"

#include <Eigen/Eigenvalues>
#include <catch2/catch.hpp>
#include <cmath>

#include "uhaptics/core/fault.hpp"

using namespace uhaptics;

TEST_CASE("ZOH of a double integrator and of a first-order lag match the analytic formulas") {
  const double T = 1e-3, m = 0.03;
  StateSpace c;
  c.A = MatX::Zero(2, 2);
  c.A(1, 0) = 1.0;  // x = (v, p)
  c.B = MatX::Zero(2, 1);
  c.B(0, 0) = 1.0 / m;
  const StateSpace d = discretizeZoh(c, T);
  CHECK(d.A(1, 0) == Approx(T).epsilon(1e-14));
  CHECK(d.B(0, 0) == Approx(T / m).epsilon(1e-14));
  CHECK(d.B(1, 0) == Approx(T * T / (2 * m)).epsilon(1e-12));

  StateSpace lag;
  lag.A = MatX::Constant(1, 1, -50.0);
  lag.B = MatX::Constant(1, 1, 2.0);
  const StateSpace dl = discretizeZoh(lag, T);
  CHECK(dl.A(0, 0) == Approx(std::exp(-50.0 * T)).epsilon(1e-14));
  CHECK(dl.B(0, 0) == Approx(2.0 * (1 - std::exp(-50.0 * T)) / 50.0).epsilon(1e-12));
  CHECK_THROWS_AS(discretizeZoh(lag, -1.0), Error);
}

TEST_CASE("Augmentation adds x_i' = r - C x and the reference input (paper eq. 7)") {
  StateSpace c;
  c.A = MatX::Identity(2, 2);
  c.B = MatX::Ones(2, 1);
  MatX C(1, 2);
  C << 0, 1;
  const StateSpace a = augmentWithIntegrators(c, C);
  REQUIRE(a.A.rows() == 3);
  CHECK(a.A(2, 1) == -1.0);
  CHECK(a.A(2, 0) == 0.0);
  CHECK(a.Bref(2, 0) == 1.0);
  CHECK(a.B(2, 0) == 0.0);
}

TEST_CASE("Linearization reproduces the Jacobians of a pendulum") {
  // x = (omega, theta), omega' = -g/l sin(theta) - c omega + u / (m l^2)
  const double g = 9.81, l = 0.2, cdamp = 0.3, mass = 0.5;
  DynamicsFunction f = [&](const VecX& x, const VecX& u, VecX& xd) {
    xd.resize(2);
    xd(0) = -g / l * std::sin(x(1)) - cdamp * x(0) + u(0) / (mass * l * l);
    xd(1) = x(0);
  };
  VecX x0(2), u0(1);
  x0 << 0.4, 0.7;
  u0 << 0.1;
  const StateSpace s = linearize(f, x0, u0);
  // Central differences: truncation O(h^2) with h ~ 6e-6: 1e-8 relative is safe.
  CHECK(s.A(0, 1) == Approx(-g / l * std::cos(0.7)).epsilon(1e-8));
  CHECK(s.A(0, 0) == Approx(-cdamp).epsilon(1e-8));
  CHECK(s.A(1, 0) == Approx(1.0).epsilon(1e-10));
  CHECK(s.B(0, 0) == Approx(1.0 / (mass * l * l)).epsilon(1e-8));
}

TEST_CASE("Full LQR-with-integrator design on a scalar mass: gain and fastest pole") {
  LqrDesignRequest req;
  const double m = 0.03;
  req.dynamics = [m](const VecX& x, const VecX& u, VecX& xd) {
    xd.resize(2);
    xd << u(0) / m, x(0);
  };
  req.x0 = VecX::Zero(2);
  req.u0 = VecX::Zero(1);
  req.C = MatX(1, 2);
  req.C << 0, 1;
  req.Q = VecX((VecX(3) << 1.0, 1e3, 1e7).finished()).asDiagonal();
  req.R = MatX::Identity(1, 1);
  const LqrDesign d = designLqrWithIntegrators(req);
  CHECK(d.dare.relative_residual < 1e-10);
  CHECK(d.K.cols() == 3);
  CHECK(d.Kc.cols() == 2);
  CHECK(d.Ki.cols() == 1);
  // Ki < 0 with this sign convention: x_i integrates r - q, u = -K x.
  CHECK(d.Ki(0, 0) < 0.0);
  CHECK(d.fastest_pole_rad_s > 10.0);  // measured ~50 rad/s for this light weighting
  CHECK(d.fastest_pole_rad_s < M_PI / req.period);
  CHECK_THROWS_WITH(
      [&] {
        LqrDesignRequest bad = req;
        bad.Q = MatX::Identity(2, 2);
        designLqrWithIntegrators(bad);
      }(),
      Catch::Contains("Q must be 3x3"));
}

namespace {
double spectralRadius(const MatX& A) {
  return Eigen::EigenSolver<MatX>(A, false).eigenvalues().cwiseAbs().maxCoeff();
}
}  // namespace

TEST_CASE("Input-delay augmentation: closed form for a scalar plant and a stable delayed loop") {
  // x+ = a x + b u_{k-1}: state (x, u_{k-1}), A = [[a, b], [0, 0]], B = [0; 1].
  const double a = 1.5, b = 1.0;
  StateSpace plant;
  plant.A = MatX::Constant(1, 1, a);
  plant.B = MatX::Constant(1, 1, b);
  plant.Bref = MatX::Constant(1, 1, 0.25);
  const StateSpace d = augmentWithInputDelay(plant, 1);
  MatX A_expected(2, 2), B_expected(2, 1), Bref_expected(2, 1);
  A_expected << a, b, 0, 0;
  B_expected << 0, 1;
  Bref_expected << 0.25, 0;  // the reference is internal to the controller: not delayed
  CHECK(d.A == A_expected);
  CHECK(d.B == B_expected);
  CHECK(d.Bref == Bref_expected);

  // A stiff design (q >> r) on the undelayed plant nearly cancels a: K0 -> a / b. On the true
  // delayed plant u_k = -K0 x_k gives z^2 - a z + b K0 = 0, whose roots multiply to b K0 ~ 1.5:
  // unstable. The design on the augmented plant accounts for the sample in flight: stable.
  const MatX Q = MatX::Constant(1, 1, 1e6), R = MatX::Identity(1, 1);
  const DareResult undelayed = solveDare(plant.A, plant.B, Q, R);
  const double K0 = undelayed.K(0, 0);
  CHECK(K0 == Approx(a / b).epsilon(1e-5));
  MatX loop_undelayed = d.A;
  loop_undelayed.row(1) = -K0 * MatX::Identity(1, 2).row(0);  // u_k = -K0 x_k enters the queue
  CHECK(spectralRadius(loop_undelayed) > 1.2);

  MatX Qa = MatX::Zero(2, 2);
  Qa(0, 0) = 1e6;  // the command in flight carries no weight of its own
  const DareResult delayed = solveDare(d.A, d.B, Qa, R);
  CHECK(spectralRadius(d.A - d.B * delayed.K) < 1.0);
  // With q >> r the delayed design is deadbeat for x: u_k = -(a^2 x_k + a b u_{k-1}) / b makes
  // x_{k+2} = 0 (closed form of the one-step predictor a x_k + b u_{k-1} = x_{k+1}).
  CHECK(delayed.K(0, 0) == Approx(a * a / b).epsilon(1e-5));
  CHECK(delayed.K(0, 1) == Approx(a).epsilon(1e-5));
}

TEST_CASE("Input-delay augmentation: shift-register structure for a MIMO plant, D = 0 unchanged") {
  StateSpace plant;
  plant.A = MatX::Random(3, 3);
  plant.B = MatX::Random(3, 2);
  const StateSpace same = augmentWithInputDelay(plant, 0);
  CHECK(same.A == plant.A);
  CHECK(same.B == plant.B);
  const int D = 3;
  const StateSpace d = augmentWithInputDelay(plant, D);
  REQUIRE(d.A.rows() == 3 + D * 2);
  REQUIRE(d.B.cols() == 2);
  // Propagate a command pulse: it must reach x exactly D samples later, through B.
  VecX s = VecX::Zero(3 + D * 2);
  VecX u(2);
  u << 1.0, -2.0;
  s = d.B * u;  // u_0 issued at k = 0
  for (int k = 1; k < D; ++k) {
    CHECK(s.head(3).isZero());
    s = d.A * s;
  }
  CHECK(s.head(3).isZero());
  s = d.A * s;  // the pulse acts over sample D
  CHECK((s.head(3) - plant.B * u).norm() < 1e-15);
  CHECK(s.tail(D * 2).isZero());
  CHECK_THROWS_AS(augmentWithInputDelay(plant, -1), Error);
  StateSpace bad = plant;
  bad.B = MatX::Zero(2, 2);
  CHECK_THROWS_AS(augmentWithInputDelay(bad, 1), Error);
}
