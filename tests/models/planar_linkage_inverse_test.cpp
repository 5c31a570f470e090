// The planar linkages' inverse kinematics against their forward kinematics: the damped Newton
// solve from a guess, the closed form along the self-motion manifold, and the wrap to the
// equivalent configuration nearest a reference; unreachable and singular targets fail clearly.
#include <Eigen/LU>
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <random>

#include "device_models.hpp"
#include "uhaptics/models/planar_linkage_model.hpp"

using namespace uhaptics;

namespace {
using Vec4 = Vec<4>;


template <int N>
Vec2 forwardOf(const PlanarLinkageModel<N>& model, const Vec<N>& q) {
  Vec2 x;
  model.forward(q, x);
  return x;
}

// Round trips for random configurations: inverse from a guess 0.3 rad away per joint, and the closed
// form from the configuration's own leading link angles, one of whose solutions is q itself.
template <int N>
void checkRoundTrips(const PlanarLinkageModel<N>& model) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> angle(-M_PI, M_PI), offset(-0.3, 0.3);
  int solved = 0;
  for (int trial = 0; trial < 200; ++trial) {
    Vec<N> q;
    for (int j = 0; j < N; ++j) q(j) = angle(rng);
    const Vec2 x = forwardOf(model, q);
    Vec<N> guess = q;
    for (int j = 0; j < N; ++j) guess(j) += offset(rng);
    const Vec<N> before = guess;
    const Fault f = model.inverse(x, guess);
    INFO("trial " << trial << ": " << toString(f));
    if (f == Fault::kNone) {
      ++solved;
      CHECK((forwardOf(model, guess) - x).norm() <= 1e-9);
    } else {
      CHECK(guess == before);  // a failure leaves the guess as it was
    }

    const auto& p = model.parameters();
    const Vec<N> phi = p.coupling * q + p.angle_offset;
    std::array<Vec<N>, 2> solutions;
    const int count = model.closeLastTwoLinks(x, phi.template head<N - 2>(), solutions);
    REQUIRE(count >= 1);
    double nearest = std::numeric_limits<double>::infinity();
    for (int k = 0; k < count; ++k) {
      const Vec<N>& s = solutions[static_cast<std::size_t>(k)];
      CHECK((forwardOf(model, s) - x).norm() <= 1e-9);
      Vec<N> wrapped;
      model.nearestEquivalent(s, q, wrapped);
      CHECK((forwardOf(model, wrapped) - x).norm() <= 1e-9);
      CHECK(((wrapped - q).array().abs() <= M_PI + 1e-12).all());
      nearest = std::min(nearest, (wrapped - q).cwiseAbs().maxCoeff());
    }
    CHECK(nearest <= 1e-9);  // one of the elbows is q's own configuration
  }
  CHECK(solved >= 190);  // a guess 0.3 rad off converges except near the singular rim
}
}  // namespace

TEST_CASE("Planar linkage inverse kinematics: round trips through the forward kinematics within 1e-9 m") {
  checkRoundTrips(test::rhi4Model());
  checkRoundTrips(test::planar3Model());
}

TEST_CASE("Planar linkage inverse kinematics: from home to reachable points of the RHI's workspace") {
  const Rhi4Model& model = test::rhi4Model();
  const Vec2 base = model.parameters().base;
  for (const Vec2& offset : {Vec2(0.1, 0.05), Vec2(-0.2, 0.1), Vec2(0.0, -0.25), Vec2(0.3, 0.3)}) {
    Vec4 q = model.homeJoints();
    REQUIRE(model.inverse(base + offset, q) == Fault::kNone);
    CHECK((forwardOf(model, q) - (base + offset)).norm() <= 1e-9);
  }
}

TEST_CASE("Planar linkage inverse kinematics: unreachable and singular targets fail clearly, no NaN") {
  const Rhi4Model& model = test::rhi4Model();
  const Vec2 base = model.parameters().base;
  const double reach = model.reach();
  const Vec4 home = model.homeJoints();

  // Outside the reachable disc.
  Vec4 q = home;
  CHECK(model.inverse(base + Vec2(1.5 * reach, 0.0), q) == Fault::kOutOfRange);
  CHECK(q == home);
  std::array<Vec4, 2> solutions;
  solutions[0] = solutions[1] = home;
  CHECK(model.closeLastTwoLinks(base + Vec2(1.5 * reach, 0.0), Vec2(0.0, 0.0), solutions) == 0);
  CHECK(solutions[0] == home);
  CHECK(solutions[1] == home);

  // Non-finite target or guess.
  CHECK(model.inverse(Vec2(std::nan(""), 0.0), q) == Fault::kNonFiniteInput);
  Vec4 bad = home;
  bad(2) = std::numeric_limits<double>::infinity();
  CHECK(model.inverse(base, bad) == Fault::kNonFiniteInput);
  CHECK(model.closeLastTwoLinks(Vec2(std::nan(""), 0.0), Vec2(0.0, 0.0), solutions) == 0);

  // Singular: every link stretched along x (J has rank 1 there) and the target straight ahead just
  // beyond the rim: no step of the damped solve reaches it, the result is a fault, q unchanged.
  const auto& p = model.parameters();
  const Vec4 stretched = p.coupling.inverse() * (Vec4::Zero() - p.angle_offset);
  REQUIRE((forwardOf(model, stretched) - (base + Vec2(reach, 0.0))).norm() < 1e-12);
  q = stretched;
  const Fault rim = model.inverse(base + Vec2(reach + 1e-6, 0.0), q);
  CHECK(rim == Fault::kOutOfRange);
  CHECK(q == stretched);
  // A target on the rim, straight ahead of the stretched arm: reached (the arm is already there) or
  // a fault; either way nothing non-finite.
  q = stretched;
  const Fault on_rim = model.inverse(base + Vec2(reach, 0.0), q);
  CHECK(q.allFinite());
  if (on_rim == Fault::kNone) CHECK((forwardOf(model, q) - (base + Vec2(reach, 0.0))).norm() <= 1e-9);
  // A target sideways of the stretched arm, inside the disc: the singular start takes bounded
  // damped steps and reaches it, or fails with q unchanged.
  q = stretched;
  const Fault sideways = model.inverse(base + Vec2(0.5 * reach, 0.3 * reach), q);
  CHECK(q.allFinite());
  if (sideways == Fault::kNone)
    CHECK((forwardOf(model, q) - (base + Vec2(0.5 * reach, 0.3 * reach))).norm() <= 1e-9);
  else
    CHECK(q == stretched);
  // The closed form on the rim, links 3-4 stretched: none when rounding puts the rim a hair beyond
  // them, else solutions that reach it.
  const int count = model.closeLastTwoLinks(base + Vec2(reach, 0.0), Vec2(0.0, 0.0), solutions);
  for (int k = 0; k < count; ++k) {
    CHECK(solutions[static_cast<std::size_t>(k)].allFinite());
    CHECK((forwardOf(model, solutions[static_cast<std::size_t>(k)]) - (base + Vec2(reach, 0.0))).norm() <= 1e-9);
  }
}

TEST_CASE("Planar linkage: whole turns of a joint are undone by the wrap to the nearest equivalent") {
  const Rhi4Model& model = test::rhi4Model();
  const Vec4 q = model.homeJoints() + Vec4(0.1, -0.2, 0.3, -0.4);
  const Vec4 turned = q + 2.0 * M_PI * Vec4(1.0, -2.0, 0.0, 3.0);
  CHECK((forwardOf(model, turned) - forwardOf(model, q)).norm() < 1e-12);
  Vec4 back;
  model.nearestEquivalent(turned, model.homeJoints(), back);
  CHECK((back - q).cwiseAbs().maxCoeff() < 1e-12);
}
