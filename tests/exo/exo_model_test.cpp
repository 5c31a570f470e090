#include "uhaptics/models/exo_finger_model.hpp"

#include <Eigen/LU>
#include <catch2/catch.hpp>
#include <cmath>

#include "device_models.hpp"
#include "uhaptics/core/finite_difference.hpp"
#include "uhaptics/models/param_file.hpp"

using namespace uhaptics;

namespace {
const std::string kParams = test::paramsPath("exo_finger.json");
std::string shippedText() { return test::readFile(kParams); }
// Replaces the first occurrence of `from` in the shipped file.
std::string edited(const std::string& from, const std::string& to) {
  std::string t = shippedText();
  const auto pos = t.find(from);
  REQUIRE(pos != std::string::npos);
  return t.replace(pos, from.size(), to);
}
ExoFingerModel::TaskVector gridPoint(const ExoFingerModel& m, int i, int j, int n) {
  return m.taskLower() + (m.taskUpper() - m.taskLower())
                             .cwiseProduct(ExoFingerModel::TaskVector(double(i) / (n - 1), double(j) / (n - 1)));
}
}  // namespace

TEST_CASE("shipped parameters load and describe an L16-class finger module") {
  const auto& m = test::exoModel();
  CHECK(m.effortLimits()(0) == 50.0);
  CHECK(m.jointLimits().upper(0) - m.jointLimits().lower(0) == Approx(0.050));
  CHECK(m.hostRateHz() == 500.0);
  CHECK(m.taskUpper()(0) == Approx(M_PI / 2));
  CHECK(m.taskUpper()(1) == Approx(100.0 * M_PI / 180.0));
}

TEST_CASE("analytic Jacobian matches central differences over the whole working range") {
  const auto& m = test::exoModel();
  constexpr int n = 61;
  double worst = 0.0;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      ExoFingerModel::JointVector q;
      REQUIRE(m.inverse(gridPoint(m, i, j, n), q));
      ExoFingerModel::Jacobian J;
      m.jacobian(q, J);
      const auto f = [&](const ExoFingerModel::JointVector& qq) {
        ExoFingerModel::TaskVector x;
        m.forward(qq, x);
        return x;
      };
      // One absolute step for both joints: l_x ~ 0.13 m and q_B ~ 1 rad are both O(0.1..1).
      const ExoFingerModel::Jacobian Jfd = centralDifferenceJacobian(f, q, 1e-6);
      worst = std::max(worst, ((J - Jfd).cwiseAbs().array() / (1.0 + Jfd.cwiseAbs().array())).maxCoeff());
    }
  }
  INFO("worst relative Jacobian error " << worst);
  // Central differences with h = 1e-6 on entries of O(1)..O(100): truncation ~ h^2 |f'''| and
  // round-off ~ eps/h give ~1e-8 at most; 1e-6 leaves margin yet catches any sign or term slip.
  CHECK(worst < 1e-6);
}

TEST_CASE("the map is one-to-one with a nonsingular Jacobian on a dense grid") {
  const auto& m = test::exoModel();
  constexpr int n = 201;  // 0.45 deg x 0.5 deg steps
  double min_abs_det = 1e300, max_abs_det = 0.0, worst_roundtrip = 0.0;
  double sign = 0.0;
  bool sign_flip = false;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const auto x = gridPoint(m, i, j, n);
      ExoFingerModel::JointVector q;
      REQUIRE(m.inverse(x, q));
      CHECK(m.inWorkingRange(q, 1e-9));
      ExoFingerModel::TaskVector back;
      m.forward(q, back);
      worst_roundtrip = std::max(worst_roundtrip, (back - x).cwiseAbs().maxCoeff());
      ExoFingerModel::Jacobian J;
      m.jacobian(q, J);
      const double det = J.determinant();
      if (sign != 0.0 && det * sign <= 0.0) sign_flip = true;
      sign = det > 0 ? 1.0 : -1.0;
      min_abs_det = std::min(min_abs_det, std::abs(det));
      max_abs_det = std::max(max_abs_det, std::abs(det));
    }
  }
  // And the other way round: every grid state of the joint box that assembles inside the working
  // range comes back to itself, so no two states share a finger pose (f is injective there).
  double worst_joint_roundtrip = 0.0;
  int states = 0;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const ExoFingerModel::JointVector q =
          m.jointLimits().lower + (m.jointLimits().upper - m.jointLimits().lower)
                               .cwiseProduct(ExoFingerModel::JointVector(double(i) / (n - 1), double(j) / (n - 1)));
      if (!m.inWorkingRange(q)) continue;
      ++states;
      ExoFingerModel::TaskVector x;
      m.forward(q, x);
      ExoFingerModel::JointVector back;
      REQUIRE(m.inverse(x, back));
      worst_joint_roundtrip = std::max(worst_joint_roundtrip, (back - q).cwiseAbs().maxCoeff());
    }
  }
  INFO("det J in [" << min_abs_det << ", " << max_abs_det << "] rad^2/m, round trips " << worst_roundtrip << " rad, "
                    << worst_joint_roundtrip << " over " << states << " joint states");
  CHECK_FALSE(sign_flip);
  // |det J| = |dMCP/dl| |dPIP/dq_B|: bounded well away from zero (rad/m units, values ~10..200).
  CHECK(min_abs_det > 20.0);
  CHECK(worst_roundtrip < 1e-10);
  CHECK(worst_joint_roundtrip < 1e-10);
  CHECK(states > n * n / 4);
  // Nonlinear: the Jacobian changes substantially across the range (an affine map has a constant det).
  CHECK(max_abs_det / min_abs_det > 2.0);
}

TEST_CASE("phalanx points follow the joint angles") {
  const auto& m = test::exoModel();
  ExoFingerPoints p;
  m.points(ExoFingerModel::TaskVector(0.0, 0.0), p);
  CHECK(p.fingertip.isApprox(Vec2(0.073, 0.0)));
  m.points(ExoFingerModel::TaskVector(M_PI / 2, M_PI / 2), p);
  CHECK((p.pip - Vec2(0.0, 0.045)).norm() < 1e-12);
  CHECK((p.fingertip - Vec2(-0.028, 0.045)).norm() < 1e-12);
  CHECK((p.middle_contact - Vec2(-0.014, 0.045)).norm() < 1e-12);
}

TEST_CASE("malformed or out-of-range parameter files are refused with a clear message") {
  const auto loadText = [](const std::string& text) { return ExoFingerModel::fromParams(ParamFile::parse(text, "exo.json")); };
  CHECK_NOTHROW(loadText(shippedText()));
  CHECK_THROWS_WITH(loadText("{ not json"), Catch::Contains("not valid JSON"));
  CHECK_THROWS_WITH(loadText(edited("\"exo_finger\"", "\"tau\"")), Catch::Contains("expected 'exo_finger'"));
  CHECK_THROWS_WITH(loadText(edited("\"value\": 0.045", "\"value\": 0.45")),
                    Catch::Contains("finger/proximal_length") && Catch::Contains("outside"));
  CHECK_THROWS_WITH(loadText(edited("\"force_limit\"", "\"force_limit_typo\"")),
                    Catch::Contains("missing required field 'actuator/force_limit'"));
  CHECK_THROWS_WITH(loadText(edited("\"value\": 50.0", "\"value\": \"fifty\"")),
                    Catch::Contains("actuator/force_limit") && Catch::Contains("must be a number"));
  CHECK_THROWS_WITH(loadText(edited("\"value\": 0.050", "\"value\": 0.030")), Catch::Contains("outside the stroke"));
  CHECK_THROWS_WITH(loadText(edited("\"value\": [0.0, 1.5707963267948966]", "\"value\": [1.0, 0.5]")),
                    Catch::Contains("mcp_range") && Catch::Contains("increasing"));
  CHECK_THROWS_WITH(loadText(edited("\"value\": 0.0225", "\"value\": 0.005")), Catch::Contains("linkage"));
  CHECK_THROWS_WITH(loadText(edited("\"value\": 1, \"source\"", "\"value\": 0, \"source\"")),
                    Catch::Contains("four_bar_mode"));
  CHECK_THROWS_WITH(ExoFingerModel::load("/nonexistent/exo.json"), Catch::Contains("cannot open"));
}
