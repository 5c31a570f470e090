#include "uhaptics/core/kinematic_model.hpp"

#include <catch2/catch.hpp>

namespace {
// A planar two-link arm: the smallest model that satisfies the interface.
struct TwoLink {
  static constexpr int kJoints = 2, kActuated = 2, kTask = 2;
  using Selection = uhaptics::Mat<2, 2>;
  void forward(const uhaptics::Vec2& q, uhaptics::Vec2& x) const noexcept {
    x << std::cos(q(0)) + std::cos(q(0) + q(1)), std::sin(q(0)) + std::sin(q(0) + q(1));
  }
  void jacobian(const uhaptics::Vec2&, uhaptics::Mat2& J) const noexcept { J.setIdentity(); }
  const Selection& selection() const noexcept { return s_; }
  Selection s_ = Selection::Identity();
};
struct NotAModel {
  static constexpr int kJoints = 2;
};
}  // namespace

TEST_CASE("the kinematic-model trait accepts models and rejects other types") {
  STATIC_REQUIRE(uhaptics::kIsKinematicModel<TwoLink>);
  STATIC_REQUIRE_FALSE(uhaptics::kIsKinematicModel<NotAModel>);
  STATIC_REQUIRE_FALSE(uhaptics::kIsKinematicModel<int>);
}

namespace {
struct WithInverse : TwoLink {
  bool inverse(const uhaptics::Vec2& x, uhaptics::Vec2& q) const noexcept {
    q = x;
    return true;
  }
};
}  // namespace

TEST_CASE("the inverse-kinematics capability is detected only where a model has it") {
  STATIC_REQUIRE(uhaptics::kHasInverseKinematics<WithInverse>);
  STATIC_REQUIRE_FALSE(uhaptics::kHasInverseKinematics<TwoLink>);
}
