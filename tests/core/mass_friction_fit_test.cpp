#include <catch2/catch.hpp>
#include <cmath>
#include <random>

#include "uhaptics/core/mass_friction_fit.hpp"

using namespace uhaptics;

namespace {
// A 1-DoF plant m a = F - b v - f_c tanh(v / v_s) driven by a known multi-sine force plus a
// centring spring (so it oscillates about its start instead of drifting), integrated with
// semi-implicit Euler at 0.1 ms; samples carry the exact acceleration of the step.
std::vector<MotionForceSample> simulatePlant(double m, double b, double fc, double amplitude, double noise,
                                             std::mt19937& rng) {
  std::normal_distribution<double> n01;
  const double dt = 1e-4, v_s = 1e-4, k = 50.0;
  double x = 0.0, v = 0.0;
  std::vector<MotionForceSample> out;
  for (int i = 0; i < 40000; ++i) {
    const double t = i * dt;
    const double force = amplitude * (std::sin(2 * M_PI * 1.3 * t) + 0.7 * std::sin(2 * M_PI * 4.1 * t + 1.0)) - k * x;
    const double a = (force - b * v - fc * std::tanh(v / v_s)) / m;
    if (i % 10 == 0) out.push_back({a, v, force + noise * n01(rng)});
    v += a * dt;
    x += v * dt;
  }
  return out;
}
}  // namespace

TEST_CASE("mass-friction least squares recovers a known 1-DoF plant") {
  std::mt19937 rng(5);
  const double m = 0.12, b = 0.45, fc = 0.08;
  SECTION("noise-free: exact up to the Coulomb smoothing") {
    const auto fit = fitMassFriction(simulatePlant(m, b, fc, 1.0, 0.0, rng), 5e-3);
    REQUIRE(fit.valid);
    // |v| >= 5e-3 = 50 v_s: tanh differs from sign by < 1e-21; what is left is rounding.
    CHECK(fit.mass == Approx(m).epsilon(1e-6));
    CHECK(fit.viscous == Approx(b).epsilon(1e-6));
    CHECK(fit.coulomb == Approx(fc).epsilon(1e-6));
    CHECK(fit.rms < 1e-9);
  }
  SECTION("10 mN force noise (a JR3-class sensor): within a few percent") {
    const auto fit = fitMassFriction(simulatePlant(m, b, fc, 1.0, 0.01, rng), 5e-3);
    REQUIRE(fit.valid);
    // ~4000 samples, noise 1 % of the force amplitude: standard errors are well below 1 %; 3 % is
    // a margin that a wrong regressor (e.g. a missing Coulomb term) could not meet.
    CHECK(fit.mass == Approx(m).epsilon(0.03));
    CHECK(fit.viscous == Approx(b).epsilon(0.03));
    CHECK(fit.coulomb == Approx(fc).epsilon(0.03));
    CHECK(fit.rms == Approx(0.01).epsilon(0.1));
  }
  SECTION("the two-term model of the paper absorbs Coulomb friction into a biased viscous term") {
    const auto fit = fitMassFriction(simulatePlant(m, b, fc, 1.0, 0.0, rng), 5e-3, false);
    REQUIRE(fit.valid);
    CHECK(fit.coulomb == 0.0);
    CHECK(fit.viscous > 1.1 * b);
  }
}

TEST_CASE("mass-friction fit refuses data that cannot determine it") {
  std::vector<MotionForceSample> still(100, MotionForceSample{0.0, 0.0, 1.0});
  CHECK_FALSE(fitMassFriction(still, 1e-3).valid);  // all inside the dead band
  std::vector<MotionForceSample> constant(100, MotionForceSample{0.0, 0.1, 1.0});
  CHECK_FALSE(fitMassFriction(constant, 1e-3).valid);  // zero acceleration column
  std::vector<MotionForceSample> collinear;
  for (int i = 1; i <= 100; ++i) collinear.push_back({0.01 * i, 0.02 * i, 0.3 * i});  // a and v proportional
  CHECK_FALSE(fitMassFriction(collinear, 1e-3, false).valid);
}
