#include <Eigen/Dense>
#include <catch2/catch.hpp>
#include <random>

#include "uhaptics/core/ellipsoid_transition.hpp"
#include "uhaptics/core/force_manipulability.hpp"
#include "uhaptics/core/null_space.hpp"
#include "uhaptics/core/saturation_observer.hpp"

using namespace uhaptics;

namespace {
Mat2 randomSpd(std::mt19937& rng) {
  std::normal_distribution<double> n01;
  Mat2 A;
  A << n01(rng), n01(rng), n01(rng), n01(rng);
  return A * A.transpose() + 0.1 * Mat2::Identity();
}
}  // namespace

TEST_CASE("log-det divergence is zero only at equality, symmetric, and G is its derivative") {
  std::mt19937 rng(1);
  for (int trial = 0; trial < 50; ++trial) {
    const Mat2 X = randomSpd(rng), Y = randomSpd(rng);
    double nu = 0.0, nu_same = 1.0, nu_swapped = 0.0;
    Mat2 G;
    REQUIRE(fme::logDetDivergence(X, Y, nu, &G));
    REQUIRE(fme::logDetDivergence(X, X, nu_same));
    REQUIRE(fme::logDetDivergence(Y, X, nu_swapped));
    CHECK(nu > 0.0);
    CHECK(std::abs(nu_same) < 1e-14);
    CHECK(nu == Approx(nu_swapped).epsilon(1e-12));
    // Directional derivative along a symmetric dX: tr(G dX) vs central difference (h = 1e-6).
    Mat2 dX = randomSpd(rng) - randomSpd(rng);
    dX = 0.5 * (dX + dX.transpose()).eval();
    const double h = 1e-6;
    double plus = 0.0, minus = 0.0;
    fme::logDetDivergence(Mat2(X + h * dX), Y, plus);
    fme::logDetDivergence(Mat2(X - h * dX), Y, minus);
    CHECK((G * dX).trace() == Approx((plus - minus) / (2 * h)).epsilon(1e-6).margin(1e-8));
  }
  Mat2 indefinite;
  indefinite << 1, 0, 0, -1;
  double nu = 0.0;
  CHECK_FALSE(fme::logDetDivergence(Mat2(Mat2::Identity()), indefinite, nu));
  CHECK(std::isnan(nu));
}

TEST_CASE("desired ellipsoids put the requested axis along the direction") {
  Mat2 M;
  REQUIRE(fme::axisAlignedEllipsoid(Vec2(0.0, 2.0), 3.3, 123.0, M));  // free motion along y
  CHECK(M.isApprox(Mat2(Vec2(123.0, 3.3).asDiagonal())));
  REQUIRE(fme::axisAlignedEllipsoid(Vec2(1.0, 1.0), 10.0, 1.0, M));
  CHECK((M * Vec2(1, 1)).isApprox(10.0 * Vec2(1, 1)));
  CHECK((M * Vec2(1, -1)).isApprox(Vec2(1, -1)));
  CHECK_FALSE(fme::axisAlignedEllipsoid(Vec2(Vec2::Zero()), 1.0, 1.0, M));
  CHECK_FALSE(fme::axisAlignedEllipsoid(Vec2(1, 0), 0.0, 1.0, M));
}

TEST_CASE("saturation observer is 1 at rest, 0 at a limit and always in [0, 1]") {
  const Vec<4> limits(3, 3, 1, 1);
  CHECK(saturationObserver<4>(Vec<4>::Zero(), limits, 50.0) == Approx(1.0));
  CHECK(saturationObserver<4>(Vec<4>(0, 3, 0, 0), limits, 50.0) == 0.0);
  // Two joints beyond their limits: eq. 14 as printed would turn positive again; ours stays 0.
  CHECK(saturationObserver<4>(Vec<4>(5, 5, 0, 0), limits, 50.0) == 0.0);
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  for (int i = 0; i < 1000; ++i) {
    const Vec<4> tau = limits.cwiseProduct(Vec<4>(u(rng), u(rng), u(rng), u(rng)));
    const double v = saturationObserver<4>(tau, limits, 50.0);
    CHECK(v >= 0.0);
    CHECK(v <= 1.0);
    // Monotone along a ray from the centre: more load, less tank.
    CHECK(saturationObserver<4>(Vec<4>(0.5 * tau), limits, 50.0) >= v);
  }
  CHECK(saturationObserver<2>(Vec2(std::nan(""), 0.0), Vec2(1, 1), 50.0) == 0.0);
}

TEST_CASE("ellipsoid transition: hysteresis, cosine blend of the right duration, continuity") {
  EllipsoidTransitionOptions opt;  // eps1 0.7, eps2 0.95, rho 0.003
  EllipsoidTransition tr;
  const double distance = 169.3;   // |diag(123, 3.3) - diag(3.3, 123)|_F
  const double duration = opt.rho * distance;
  const double dt = 1e-3;
  double t = 0.0, previous = 1.0, max_step = 0.0;
  auto run = [&](double V, double seconds) {
    for (double end = t + seconds; t < end; t += dt) {
      const double w = tr.update(t, V, distance, opt);
      max_step = std::max(max_step, std::abs(w - previous));
      previous = w;
    }
  };
  run(0.8, 0.5);  // above eps1: stays free
  CHECK(tr.omega() == 1.0);
  run(0.6, duration / 2);  // below eps1: halfway through the blend
  CHECK(tr.omega() == Approx(0.5).margin(0.01));
  run(0.9, duration);  // between the thresholds: keeps going to stiff (no chattering)
  CHECK(tr.omega() == 0.0);
  run(0.96, duration + 0.01);  // above eps2: back to free
  CHECK(tr.omega() == 1.0);
  // Half-cosine over T: the largest per-tick change is pi / (2 T) dt.
  CHECK(max_step <= M_PI / (2.0 * duration) * dt * 1.001);
  opt.smooth = false;
  tr.reset();
  CHECK(tr.update(0.0, 0.5, distance, opt) == 0.0);  // jumps at once
}

TEST_CASE("dynamically consistent null-space projector annihilates end-effector force and acceleration") {
  std::mt19937 rng(9);
  std::normal_distribution<double> n01;
  for (int trial = 0; trial < 20; ++trial) {
    Mat<2, 4> J;
    Mat<4, 4> A;
    for (int i = 0; i < 8; ++i) J(i) = n01(rng);
    for (int i = 0; i < 16; ++i) A(i) = n01(rng);
    const Mat<4, 4> Minv = (A * A.transpose() + 0.1 * Mat<4, 4>::Identity()).inverse();
    Mat<4, 4> NT;
    Mat<4, 2> Js;
    REQUIRE(nullSpaceProjector(J, Minv, NT, &Js));
    const Vec<4> tau(n01(rng), n01(rng), n01(rng), n01(rng));
    CHECK((J * Minv * NT * tau).norm() < 1e-10 * tau.norm());  // no acceleration
    CHECK((Js.transpose() * NT * tau).norm() < 1e-10 * tau.norm());  // no force
    CHECK((J * Js).isApprox(Mat2::Identity()));
  }
  Mat<4, 4> NT;
  CHECK_FALSE(nullSpaceProjector(Mat<2, 4>(Mat<2, 4>::Zero()), Mat<4, 4>(Mat<4, 4>::Identity()), NT));
}
