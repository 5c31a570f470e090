#include "uhaptics/core/regularized_solve.hpp"

#include <Eigen/Dense>
#include <catch2/catch.hpp>
#include <limits>

#include "uhaptics/core/finite_difference.hpp"
#include "uhaptics/core/limits.hpp"
#include "uhaptics/tools/alloc_probe.hpp"

using namespace uhaptics;

TEST_CASE("regularized solve is the exact solution for a well-conditioned matrix") {
  Mat2 A;
  A << 2.0, 1.0, -1.0, 3.0;
  const Vec2 r(1.0, -2.0);
  RegularizedSolveInfo info;
  const Vec2 x = regularizedSolve(A, r, {}, &info);
  CHECK((x - A.inverse() * r).norm() < 1e-14);
  CHECK_FALSE(info.damped());
}

TEST_CASE("regularized solve returns the least-squares solution of a tall system") {
  Mat<3, 2> A;
  A << 1, 0, 0, 1, 1, 1;
  const Vec3 r(1, 2, 4);
  const Vec2 x = regularizedSolve(A, r);
  const Vec2 ref = (A.transpose() * A).ldlt().solve(A.transpose() * r);
  CHECK((x - ref).norm() < 1e-13);
}

TEST_CASE("regularized solve stays bounded and continuous through a singularity") {
  const RegularizationOptions opt{1e-3, 1e-2};
  const Vec2 r(1.0, 1.0);
  auto solveWith = [&](double s2) {
    Mat2 A = Mat2::Zero();
    A(0, 0) = 1.0;
    A(1, 1) = s2;
    return regularizedSolve(A, r, opt);
  };
  // The second singular value sweeps from well above the threshold down to exactly zero:
  // undamped |x_2| = 1/s <= 1/epsilon above the threshold, damped s/(s^2 + lambda^2) below it.
  for (double s2 = 1e-2; s2 > 1e-14; s2 *= 0.97) {
    const Vec2 x = solveWith(s2);
    REQUIRE(x.allFinite());
    CHECK(std::abs(x(1)) <= 1.0 / opt.epsilon * (1.0 + 1e-9));
  }
  // At the singularity: the seen direction is solved with damping lambda = lambda_max * s_max, the
  // unseen one is left at zero.
  CHECK(solveWith(0.0).isApprox(Vec2(1.0 / (1.0 + 1e-4), 0.0), 1e-12));
  // Continuous where damping switches on: no jump across s = epsilon * s_max.
  const Vec2 above = solveWith(opt.epsilon * (1.0 + 1e-9));
  const Vec2 below = solveWith(opt.epsilon * (1.0 - 1e-9));
  CHECK((above - below).norm() < 1e-3 * above.norm());
}

TEST_CASE("regularized solve of non-finite input gives zero") {
  Mat2 A = Mat2::Identity();
  A(0, 1) = std::numeric_limits<double>::quiet_NaN();
  const Vec2 x = regularizedSolve(A, Vec2(1, 1));
  CHECK(x.isZero());
  const Vec2 y = regularizedSolve(Mat2::Identity().eval(), Vec2(std::numeric_limits<double>::infinity(), 0));
  CHECK(y.isZero());
}

TEST_CASE("fixed-size regularized solve allocates nothing") {
  Mat<2, 2> A;
  A << 1, 2, 3, 4;
  const Vec2 r(1, 1);
  tools::AllocationScope scope;
  volatile double sink = regularizedSolve(A, r).sum();
  (void)sink;
  CHECK(scope.count() == 0);
}

TEST_CASE("central-difference Jacobian matches an analytic one") {
  auto f = [](const Vec2& x) { return Vec2(std::sin(x(0)) * x(1), x(0) * x(0) + std::exp(x(1))); };
  const Vec2 x(0.3, -0.7);
  Mat2 J;
  J << std::cos(x(0)) * x(1), std::sin(x(0)), 2 * x(0), std::exp(x(1));
  CHECK((centralDifferenceJacobian(f, x) - J).norm() < 1e-9);
}

TEST_CASE("limits: clamp, direction-preserving scaling, non-finite guard") {
  Vec3 c(3.0, -0.5, -4.0);
  const Vec3 lim(2.0, 2.0, 2.0);
  Vec3 scaled = c;
  const double alpha = scaleIntoBox(scaled, lim);
  CHECK(alpha == Approx(0.5));
  CHECK(scaled.normalized().isApprox(c.normalized()));
  CHECK(clampSymmetric(c, lim) == 2);
  CHECK(c == Vec3(2.0, -0.5, -2.0));
  Vec3 bad(1.0, std::numeric_limits<double>::quiet_NaN(), 0.0);
  CHECK(zeroIfNonFinite(bad) == Fault::kNonFiniteResult);
  CHECK(bad.isZero());
}
