#include "uhaptics/experiments/policy_servo.hpp"

#include <algorithm>
#include <cmath>

#include "uhaptics/core/fault.hpp"

namespace uhaptics::experiments {

PolicyServo::PolicyServo(DevicePolicy& policy, const BoardSpec& spec)
    : policy_(policy),
      joints_(spec.descriptor.joints),
      actuators_(spec.descriptor.actuators),
      dt_(1.0 / spec.servo_rate_hz) {
  if (joints_ < 1 || joints_ > wire::kMaxChannels || joints_ > kMaxSensedJoints || actuators_ < 1 ||
      actuators_ > joints_ || !(spec.servo_rate_hz > 0.0))
    throw Error("PolicyServo: the board's joint and actuator counts or its servo rate are out of range");
  rate_.setResolution(spec.position_resolution.data(), joints_);
}

void PolicyServo::reset(int command_delay) {
  policy_.reset(command_delay);
  rate_.reset();
  first_ = true;
  ticks_ = 0;
  faults_ = 0;
}

const SensedState& PolicyServo::sense(const double* positions, int applied_age) noexcept {
  // The board's sample clock: one sample per servo period.
  const auto sample_us = static_cast<std::uint32_t>(std::llround(static_cast<double>(ticks_) * dt_ * 1e6));
  rate_.update(positions, joints_, sample_us, rates_.data());
  policy_.sense(SensedJoints{positions, rates_.data(), first_}, state_);
  if (applied_age >= 0) policy_.commandApplied(applied_age);
  return state_;
}

Fault PolicyServo::render(const Vec3& force, double* efforts) noexcept {
  SceneInput input;
  input.time = static_cast<double>(ticks_) * dt_;
  input.dt = dt_;
  input.force = force;
  input.seen_position = state_.position;  // the scene's force is from this period's reading
  first_ = false;
  ++ticks_;
  Fault fault = policy_.render(input, efforts);
  for (int i = 0; i < actuators_; ++i) {
    if (!std::isfinite(efforts[i]) && fault == Fault::kNone) fault = Fault::kNonFiniteResult;
  }
  if (fault != Fault::kNone) {
    ++faults_;
    std::fill(efforts, efforts + actuators_, 0.0);
  }
  return fault;
}

}  // namespace uhaptics::experiments
