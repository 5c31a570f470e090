// The CHAI3D RHI scene's palpation without CHAI3D: a scripted hand (150 N/m, at most 8 N) presses
// a stiff wall (K_e = 1000 N/m, 2 cm below home) from home in automatic mode. The free-to-stiff
// switch swings the arm along its self-motion at up to 15 rad/s (beta = 20); the joint-limit
// barrier, a potential, cannot dissipate that, so without the approach-speed damper the arm reaches
// a mechanical stop, whose reaction is not in the null space, and the end effector is kicked through
// the wall (16 N asked of a hand that pushes 8).
#include <catch2/catch.hpp>

#include "rhi_fixtures.hpp"
#include "uhaptics/backends/scripted_hand.hpp"
#include "uhaptics/experiments/rhi_experiments.hpp"

using namespace uhaptics;

namespace {
struct PressResult {
  double peak_demand = 0.0;     // largest wall force asked for [N]
  double limit_distance = 1e9;  // closest approach to a joint limit [rad]
};

PressResult pressFromHome(const rhi::Rhi4Controller::Options& options) {
  const auto& m = rhi_test::rhi4();
  Vec2 home_tip;
  m.forward(m.homeJoints(), home_tip);
  rhi::PalpationSetup setup;
  setup.x0 = home_tip + Vec2(0.0, 0.02);  // the scene's tissue top, 2 cm "below" home along u = +y
  rhi::ClosedLoop loop(m, rhi_test::rhi4Product(), options, setup);
  loop.reset(m.homeJoints());
  // The scene's hand path in workspace radii (0.1 m) of the device frame (task x -> y, task y -> -z).
  ScriptedHandOptions hand_options;
  hand_options.waypoints = {Vec3(0.0, -0.4, 0.1), Vec3(0.0, -0.4, -0.55), Vec3(0.0, -0.4, 0.1)};
  hand_options.lap_time = 3.0;
  const ScriptedHand hand(hand_options, 0.1, Vec3::Zero());
  PressResult r;
  for (int k = 0; k < 3000; ++k) {
    const Vec2 x = loop.device().endEffectorPosition() - home_tip, v = loop.device().endEffectorVelocity();
    const Vec3 f = hand.force(loop.time(), Vec3(0.0, x.x(), -x.y()), Vec3(0.0, v.x(), -v.y()));
    EndEffectorLoad load;
    load.bias = Vec2(f.y(), -f.z());
    loop.tick(load, true);
    const auto s = loop.sample();
    r.peak_demand = std::max(r.peak_demand, s.demanded);
    r.limit_distance = std::min(r.limit_distance, s.limit_distance);
  }
  return r;
}
}  // namespace

TEST_CASE("scene press: the free-to-stiff swing never kicks the end effector through a stiff wall") {
  const PressResult r = pressFromHome({});
  // The device holds the hand: the wall force asked for stays near the hand's 8 N (dynamics of the
  // 150 N/m hand and 4 N s/m damping add a little; 25 %). A kick gives twice that.
  CHECK(r.peak_demand < 1.25 * 8.0);
  CHECK(r.limit_distance > 0.0);
  // The failure this guards against is real: without the damper the swing hits a stop.
  rhi::Rhi4Controller::Options undamped;
  undamped.limit_speed = 0.0;
  const PressResult kicked = pressFromHome(undamped);
  CHECK(kicked.limit_distance < 0.0);
  CHECK(kicked.peak_demand > 1.25 * 8.0);
}
