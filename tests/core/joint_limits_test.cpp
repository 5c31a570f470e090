#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <random>

#include "uhaptics/core/finite_difference.hpp"
#include "uhaptics/core/joint_limits.hpp"

using namespace uhaptics;

namespace {
// A parallelogram-style coupled limit: q0 in [-1, 1], internal angle q0 - q1 in [-0.5, 0.5], q2 free.
JointLimits<3> coupledLimits() {
  JointLimits<3> l;
  l.map << 1, 0, 0, 1, -1, 0, 0, 0, 1;
  l.lower = Vec3(-1.0, -0.5, -std::numeric_limits<double>::infinity());
  l.upper = Vec3(1.0, 0.5, std::numeric_limits<double>::infinity());
  return l;
}
}  // namespace

TEST_CASE("joint limits: distance, containment and validation") {
  const auto l = coupledLimits();
  REQUIRE(l.valid());
  CHECK(l.any());
  CHECK_FALSE(JointLimits<3>{}.any());
  CHECK(l.distance(Vec3(0.0, 0.0, 100.0)) == Approx(0.5));
  CHECK(l.distance(Vec3(0.9, 0.9, 0.0)) == Approx(0.1));   // q0 near its upper bound
  CHECK(l.distance(Vec3(0.2, -0.5, 0.0)) == Approx(-0.2)); // q0 - q1 = 0.7 violates 0.5
  CHECK_FALSE(l.contains(Vec3(0.2, -0.5, 0.0)));
  auto bad = l;
  bad.lower(1) = 0.6;  // lower above upper
  CHECK_FALSE(bad.valid());
  bad = l;
  bad.map(0, 0) = std::numeric_limits<double>::quiet_NaN();
  CHECK_FALSE(bad.valid());
}

TEST_CASE("joint-limit barrier: zero away from the limits, C1, gradient matches differences, repels") {
  const auto l = coupledLimits();
  const double margin = 0.25;
  Vec3 g;
  jointLimitGradient(l, Vec3(0.1, 0.05, 3.0), margin, g);
  CHECK(jointLimitPotential(l, Vec3(0.1, 0.05, 3.0), margin) == 0.0);
  CHECK(g.isZero(0.0));
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> box(-1.2, 1.2);
  int active = 0;
  for (int i = 0; i < 500; ++i) {
    const Vec3 q(box(rng), box(rng), box(rng));
    jointLimitGradient(l, q, margin, g);
    // Central differences of P (h ~ 6e-6): P is C1 with bounded curvature except right at the floor,
    // so 1e-5 relative + 1e-7 absolute covers the truncation error.
    for (int k = 0; k < 3; ++k) {
      Vec3 qp = q, qm = q;
      const double h = centralDifferenceStep(q(k));
      qp(k) += h;
      qm(k) -= h;
      const double fd = (jointLimitPotential(l, qp, margin) - jointLimitPotential(l, qm, margin)) / (2 * h);
      CHECK(g(k) == Approx(fd).epsilon(1e-5).margin(1e-7));
    }
    if (!g.isZero(0.0)) ++active;
    // Descending P moves away from the nearest limit: -g increases the distance to first order.
    if (l.distance(q) > 0.0 && !g.isZero(0.0)) {
      const Vec3 step = -1e-6 * g / g.norm();
      CHECK(l.distance(q + step) >= l.distance(q) - 1e-12);
    }
  }
  CHECK(active > 100);
  // Continuity at the edge of the margin (P and its slope both vanish there).
  const double edge = 1.0 - margin;
  CHECK(jointLimitPotential(l, Vec3(edge - 1e-7, edge - 1e-7, 0.0), margin) < 1e-12);
  // Finite and growing without bound towards the limit, linear (finite) beyond it.
  const double near = jointLimitPotential(l, Vec3(0.999, 0.999, 0.0), margin);
  const double beyond = jointLimitPotential(l, Vec3(1.2, 1.2, 0.0), margin);
  CHECK(near > 3.0);
  CHECK(std::isfinite(beyond));
  CHECK(beyond > near);
}
