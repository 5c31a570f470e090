// PolicyServo: what an experiment's policy gets each period is what the hardware path hands it (the
// joints as read, rates from the shared estimator, the board's report of the applied command), and a
// fault or a non-finite effort reaches the plant as zero.
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>

#include "uhaptics/experiments/policy_servo.hpp"

using namespace uhaptics;

namespace {
// Records what it was handed; renders `effort` on its one actuator.
class RecordingPolicy final : public DevicePolicy {
 public:
  std::string name() const override { return "recording"; }
  void reset(int command_delay) override {
    delay = command_delay;
    resets += 1;
  }
  void sense(const SensedJoints& reading, SensedState& state) noexcept override {
    position = reading.positions[0];
    rate = reading.rates[0];
    first = reading.first;
    state.position = Vec3(position, 0.0, 0.0);
  }
  void commandApplied(int periods_ago) noexcept override { applied_age = periods_ago; }
  Fault render(const SceneInput& input, double* efforts) noexcept override {
    input_ = input;
    efforts[0] = effort;
    return fault;
  }

  int delay = -1, resets = 0, applied_age = -1;
  double position = 0.0, rate = 0.0, effort = 1.0;
  bool first = false;
  Fault fault = Fault::kNone;
  SceneInput input_;
};

BoardSpec oneJoint(double resolution) {
  BoardSpec spec;
  spec.descriptor.joints = 1;
  spec.descriptor.actuators = 1;
  spec.servo_rate_hz = 1000.0;
  spec.position_resolution[0] = resolution;
  return spec;
}
}  // namespace

TEST_CASE("PolicyServo hands the policy the reading, the estimated rate and the board's applied command") {
  RecordingPolicy policy;
  experiments::PolicyServo servo(policy, oneJoint(0.0));
  servo.reset(2);
  CHECK(policy.delay == 2);
  double effort = 0.0;
  // A joint moving at 0.5 rad/s: the estimator's rate reaches it from the readings alone.
  for (int k = 0; k < 30; ++k) {
    const double q = 0.5 * k * 1e-3;
    servo.sense(&q, k % 4 == 0 ? -1 : k % 4);
    CHECK(policy.first == (k == 0));
    CHECK(policy.position == q);
    CHECK(policy.applied_age == (k % 4 == 0 ? (k == 0 ? -1 : 3) : k % 4));  // none reported: unchanged
    CHECK(servo.render(Vec3(1.0, 0.0, 0.0), &effort) == Fault::kNone);
    CHECK(policy.input_.time == Approx(k * 1e-3));
    CHECK(policy.input_.seen_position.x() == q);  // the scene's force is from this reading
    CHECK(effort == 1.0);
  }
  CHECK(policy.rate == Approx(0.5).epsilon(1e-6));
  // A new session starts the clock and the estimator again.
  servo.reset(0);
  const double q = 1.0;
  servo.sense(&q);
  CHECK(policy.first);
  CHECK(policy.rate == 0.0);
}

TEST_CASE("PolicyServo sends zero for a fault or a non-finite effort and counts them") {
  RecordingPolicy policy;
  experiments::PolicyServo servo(policy, oneJoint(0.0015));
  servo.reset(0);
  const double q = 0.0;
  double effort = 0.0;
  servo.sense(&q);
  policy.effort = std::numeric_limits<double>::quiet_NaN();
  CHECK(servo.render(Vec3::Zero(), &effort) == Fault::kNonFiniteResult);
  CHECK(effort == 0.0);
  policy.effort = 2.0;
  policy.fault = Fault::kSingular;
  CHECK(servo.render(Vec3::Zero(), &effort) == Fault::kSingular);
  CHECK(effort == 0.0);
  CHECK(servo.faults() == 2);
}

TEST_CASE("PolicyServo refuses a board it cannot serve") {
  RecordingPolicy policy;
  BoardSpec no_rate = oneJoint(0.0);
  no_rate.servo_rate_hz = 0.0;
  CHECK_THROWS_AS(experiments::PolicyServo(policy, no_rate), Error);
  BoardSpec too_many = oneJoint(0.0);
  too_many.descriptor.joints = wire::kMaxChannels + 1;
  CHECK_THROWS_AS(experiments::PolicyServo(policy, too_many), Error);
}
