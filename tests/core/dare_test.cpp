#include "uhaptics/core/dare.hpp"

#include <catch2/catch.hpp>
#include <cmath>

#include "uhaptics/core/fault.hpp"

using namespace uhaptics;

namespace {
MatX scalar(double v) { return MatX::Constant(1, 1, v); }
// Scalar DARE p = a^2 p - a^2 b^2 p^2 / (r + b^2 p) + q  <=>  b^2 p^2 + (r - a^2 r - q b^2) p - q r = 0.
double scalarDare(double a, double b, double q, double r) {
  const double B = r - a * a * r - q * b * b;
  return (-B + std::sqrt(B * B + 4.0 * b * b * q * r)) / (2.0 * b * b);
}
}  // namespace

TEST_CASE("DARE matches the closed-form scalar solution, stable and unstable plants") {
  for (double a : {0.5, 1.0, 1.2, -2.0})
    for (double q : {1e-3, 1.0, 1e6})
      for (double r : {1e-2, 1.0, 1e3}) {
        const double b = 0.7;
        const DareResult res = solveDare(scalar(a), scalar(b), scalar(q), scalar(r));
        const double p = scalarDare(a, b, q, r);
        INFO("a " << a << " q " << q << " r " << r);
        // Relative 1e-10: the closed form loses ~eps*cond digits for q/r = 1e8, still far below 1e-10.
        CHECK(res.P(0, 0) == Approx(p).epsilon(1e-10));
        CHECK(res.K(0, 0) == Approx(b * p * a / (r + b * b * p)).epsilon(1e-10));
        CHECK(res.closed_loop_spectral_radius < 1.0);
      }
}

TEST_CASE("DARE of a diagonal system is the diagonal of scalar solutions") {
  MatX A = VecX::LinSpaced(5, 0.3, 1.5).asDiagonal();
  MatX B = VecX::LinSpaced(5, 0.1, 2.0).asDiagonal();
  VecX qd(5), rd(5);
  qd << 1, 10, 1e3, 1e5, 1e7;
  rd << 1, 0.1, 1, 10, 1;
  const DareResult res = solveDare(A, B, MatX(qd.asDiagonal()), MatX(rd.asDiagonal()));
  for (int i = 0; i < 5; ++i) CHECK(res.P(i, i) == Approx(scalarDare(A(i, i), B(i, i), qd(i), rd(i))).epsilon(1e-10));
  CHECK((res.P - MatX(res.P.diagonal().asDiagonal())).norm() < 1e-9 * res.P.norm());
}

TEST_CASE("DARE stays accurate with weights spanning 1e0..1e9 on integrator chains") {
  // Discrete double integrators with an integral state (the TAU structure in miniature):
  // eigenvalues all at z = 1, Q weights 1 .. 1e9.
  const double T = 1e-3;
  for (double w : {1e0, 1e3, 1e6, 1e9}) {
    MatX A(3, 3), B(3, 1);
    A << 1, 0, 0, T, 1, 0, -0.5 * T * T, -T, 1;
    B << T / 0.03, 0.5 * T * T / 0.03, -T * T * T / 6 / 0.03;
    MatX Q = VecX((VecX(3) << 1.0, 1e3, w).finished()).asDiagonal();
    const DareResult res = solveDare(A, B, Q, MatX::Identity(1, 1));
    INFO("integral weight " << w << " residual " << res.relative_residual);
    CHECK(res.relative_residual < 1e-11);
    CHECK(res.closed_loop_spectral_radius < 1.0);
  }
}

TEST_CASE("DARE solves near-unstabilizable pairs and rejects unstabilizable/undetectable ones") {
  MatX A(2, 2), Q = MatX::Identity(2, 2), R = MatX::Identity(1, 1);
  A << 1.1, 0, 0, 0.5;
  MatX B(2, 1);
  SECTION("weakly controllable unstable mode: still solved, residual verified") {
    B << 1e-4, 1;
    const DareResult res = solveDare(A, B, Q, R);
    CHECK(res.relative_residual < 1e-9);
    CHECK(res.closed_loop_spectral_radius < 1.0);
  }
  SECTION("uncontrollable unstable mode") {
    B << 0, 1;
    REQUIRE_THROWS_AS(solveDare(A, B, Q, R), Error);
    CHECK_THROWS_WITH(solveDare(A, B, Q, R), Catch::Contains("not stabilizable"));
  }
  SECTION("unstable mode invisible to Q") {
    B << 1, 1;
    MatX Qs = MatX::Zero(2, 2);
    Qs(1, 1) = 1.0;
    CHECK_THROWS_WITH(solveDare(A, B, Qs, R), Catch::Contains("not detectable"));
  }
  SECTION("uncontrollable but stable mode is fine") {
    MatX As(2, 2);
    As << 0.9, 0, 0, 0.5;
    B << 0, 1;
    CHECK(solveDare(As, B, Q, R).relative_residual < 1e-12);
  }
  SECTION("malformed input") {
    B << 1, 1;
    CHECK_THROWS_WITH(solveDare(A, B, Q, -R), Catch::Contains("R is not positive definite"));
    MatX Qbad(2, 2);
    Qbad << 1, 0.5, 0, 1;
    CHECK_THROWS_WITH(solveDare(A, B, Qbad, R), Catch::Contains("not symmetric"));
    MatX Anan(2, 2);
    Anan << std::nan(""), 0, 0, 0.5;
    CHECK_THROWS_WITH(solveDare(Anan, B, Q, R), Catch::Contains("NaN"));
    CHECK_THROWS_WITH(solveDare(A, MatX::Ones(3, 1), Q, R), Catch::Contains("inconsistent sizes"));
  }
}
