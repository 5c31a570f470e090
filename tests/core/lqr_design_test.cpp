#include "uhaptics/core/lqr_design.hpp"

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
