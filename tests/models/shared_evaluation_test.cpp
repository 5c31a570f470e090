// The models' evaluations that share work (link angles, closures) against the single evaluations
// they replace in the servo tick: the same values, bit for bit.
#include <array>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>

#include "device_models.hpp"

using namespace uhaptics;

namespace {
struct Uniform {
  std::uint64_t seed;
  double operator()(double lo, double hi) {
    seed = seed * 6364136223846793005ULL + 1442695040888963407ULL;
    return lo + (hi - lo) * static_cast<double>(seed >> 11) / 9007199254740992.0;
  }
};

template <class Model>
void checkPlanarLinkage(const Model& m) {
  Uniform uniform{42};
  for (int trial = 0; trial < 500; ++trial) {
    typename Model::JointVector q;
    for (int i = 0; i < Model::kJoints; ++i) q(i) = uniform(-M_PI, M_PI);
    typename Model::TaskVector x, x_together;
    typename Model::Jacobian J, J_together;
    m.forward(q, x);
    m.jacobian(q, J);
    m.forwardAndJacobian(q, x_together, J_together);
    REQUIRE(x_together == x);
    REQUIRE(J_together == J);
    std::array<typename Model::Jacobian, Model::kJoints> dJ;
    m.jacobianDerivatives(q, dJ);
    for (int k = 0; k < Model::kJoints; ++k) {
      typename Model::Jacobian dJk;
      m.jacobianDerivative(q, k, dJk);
      REQUIRE(dJ[static_cast<std::size_t>(k)] == dJk);
    }
  }
}
}  // namespace

TEST_CASE("planar linkages: forwardAndJacobian and jacobianDerivatives equal forward, jacobian, jacobianDerivative") {
  checkPlanarLinkage(test::rhi4Model());
  checkPlanarLinkage(test::planar3Model());
}

TEST_CASE("finger exoskeleton: forward(q, data) equals forward, jacobian and inWorkingRange, in and out of range") {
  const ExoFingerModel& m = test::exoModel();
  Uniform uniform{7};
  int in_range = 0, trials = 0;
  for (; trials < 2000; ++trials) {
    // Each joint over its range and a fifth of it beyond either stop: in and out of the working range.
    const auto& lim = m.jointLimits();
    const ExoFingerModel::JointVector span = lim.upper - lim.lower;
    const ExoFingerModel::JointVector q(uniform(lim.lower(0) - 0.2 * span(0), lim.upper(0) + 0.2 * span(0)),
                              uniform(lim.lower(1) - 0.2 * span(1), lim.upper(1) + 0.2 * span(1)));
    ExoFingerData data(m);
    m.forward(q, data);
    ExoFingerModel::TaskVector x;
    ExoFingerModel::Jacobian J, J_from_x;
    m.forward(q, x);
    m.jacobian(q, J);
    m.jacobian(q, x, J_from_x);
    REQUIRE(data.x == x);
    REQUIRE(data.J == J);
    REQUIRE(J_from_x == J);
    REQUIRE(data.in_range == m.inWorkingRange(q));
    in_range += data.in_range ? 1 : 0;
  }
  // Both outcomes of the range check are exercised.
  CHECK(in_range > trials / 10);
  CHECK(in_range < trials - trials / 10);
}
