// The scripted hand: path geometry, spring-damper force, saturation, bad input, no allocation.
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>

#include "uhaptics/backends/scripted_hand.hpp"
#include "uhaptics/core/fault.hpp"
#include "uhaptics/tools/alloc_probe.hpp"

using uhaptics::ScriptedHand;
using uhaptics::ScriptedHandOptions;
using uhaptics::Vec3;

TEST_CASE("scripted hand anchor travels the closed path at constant speed", "[backends][hand]") {
  ScriptedHandOptions options;
  options.waypoints = {Vec3(0, 0, 1), Vec3(0, 0, -1)};  // 2 r down, 2 r up: lap = 4 r
  options.lap_time = 2.0;
  const double radius = 0.05;
  const Vec3 centre(0.01, 0.0, 0.0);
  const ScriptedHand hand(options, radius, centre);
  Vec3 p, v;
  hand.anchor(0.0, p, v);
  CHECK((p - Vec3(0.01, 0, 0.05)).norm() < 1e-12);
  CHECK(v.z() == Approx(-4 * radius / 2.0));  // lap length / lap time, heading down
  hand.anchor(0.5, p, v);                      // a quarter lap: at the centre
  CHECK((p - centre).norm() < 1e-12);
  hand.anchor(1.5, p, v);                      // three quarters: back at the centre, going up
  CHECK((p - centre).norm() < 1e-12);
  CHECK(v.z() > 0.0);
  hand.anchor(2.0 + 0.5, p, v);                // periodic
  CHECK((p - centre).norm() < 1e-12);
  hand.anchor(-0.5, p, v);                     // negative time wraps too (= 1.5 s)
  CHECK((p - centre).norm() < 1e-12);
  CHECK(v.z() > 0.0);
}

TEST_CASE("scripted hand force is a saturated spring-damper toward the anchor", "[backends][hand]") {
  ScriptedHandOptions options;
  options.waypoints = {Vec3(0, 0, 0), Vec3(1, 0, 0)};
  options.lap_time = 1e3;  // nearly still anchor
  options.stiffness = 100.0;
  options.damping = 2.0;
  options.max_force = 3.0;
  const ScriptedHand hand(options, 0.1, Vec3::Zero());
  Vec3 anchor, anchor_velocity;
  hand.anchor(0.0, anchor, anchor_velocity);
  // 1 cm below the anchor, at rest: k * 0.01 = 1 N up, plus damping on the anchor's tiny speed.
  const Vec3 f = hand.force(0.0, anchor - Vec3(0, 0, 0.01), Vec3::Zero());
  CHECK(f.z() == Approx(1.0).margin(1e-12));
  CHECK(f.x() == Approx(2.0 * anchor_velocity.x()).margin(1e-12));
  // Far away: the magnitude saturates at max_force, direction kept.
  const Vec3 g = hand.force(0.0, anchor + Vec3(0.3, 0.4, 0.0), Vec3::Zero());
  CHECK(g.norm() == Approx(3.0));
  CHECK(g.normalized().dot(Vec3(-0.6, -0.8, 0.0)) == Approx(1.0).margin(1e-6));
  // Non-finite state never produces a force.
  CHECK(hand.force(0.0, Vec3(std::numeric_limits<double>::quiet_NaN(), 0, 0), Vec3::Zero()).isZero());
  CHECK(hand.force(std::numeric_limits<double>::infinity(), Vec3::Zero(), Vec3::Zero()).isZero());
}

TEST_CASE("scripted hand evaluation allocates nothing", "[backends][hand]") {
  const ScriptedHand hand(ScriptedHandOptions{}, 0.1, Vec3::Zero());
  Vec3 sum = Vec3::Zero();
  uhaptics::tools::AllocationScope scope;
  for (int i = 0; i < 1000; ++i) sum += hand.force(1e-3 * i, Vec3::Zero(), Vec3::Zero());
  CHECK(scope.count() == 0);
  CHECK(sum.allFinite());
}

TEST_CASE("scripted hand rejects invalid options with a message", "[backends][hand]") {
  ScriptedHandOptions options;
  options.waypoints = {Vec3(0, 0, 0)};
  CHECK_THROWS_WITH(ScriptedHand(options, 0.1, Vec3::Zero()), Catch::Contains("at least two waypoints"));
  options.waypoints = {Vec3(0, 0, 0.1), Vec3(0, 0, 0.1)};
  CHECK_THROWS_WITH(ScriptedHand(options, 0.1, Vec3::Zero()), Catch::Contains("same point"));
  options.waypoints = {Vec3(0, 0, 0), Vec3(0, 0, 5)};
  CHECK_THROWS_WITH(ScriptedHand(options, 0.1, Vec3::Zero()), Catch::Contains("two workspace radii"));
  CHECK_THROWS_WITH(ScriptedHand(ScriptedHandOptions{}, -1.0, Vec3::Zero()), Catch::Contains("workspace radius"));
  ScriptedHandOptions slow;
  slow.lap_time = 0.0;
  CHECK_THROWS_WITH(ScriptedHand(slow, 0.1, Vec3::Zero()), Catch::Contains("lap_time"));
}
