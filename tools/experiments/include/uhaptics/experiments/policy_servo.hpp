#pragma once
// A device's DevicePolicy run the way the hardware path runs it, for the papers' experiments on a
// simulated plant (CHAI3D-free; shaped like tools/servo's DeviceServoRenderer, whose servo runner
// it is meant to join). Each servo period:
//
//   joint reading (sensor counts x resolution) -> JointRateEstimator over the board's sample clock
//   -> policy.sense() -> the caller's scene computes its force from the sensed state -> render()
//   -> efforts for the plant
//
// The policy is reset for the command delay the caller's plant has (0: the efforts act in the period
// after the reading they answer, as on the sim backend). Where the board names the command it
// applied (a random transport delay), the caller hands that over with the reading. The plant's truth
// is the caller's, for its metrics and the referee: nothing here reads it. sense() and render()
// never allocate or throw.
#include <array>
#include <cstdint>
#include <functional>
#include <memory>

#include "uhaptics/backends/device_definition.hpp"
#include "uhaptics/backends/joint_io.hpp"
#include "uhaptics/renderers/device_policy.hpp"

namespace uhaptics::experiments {

/// A device as the product runs it: its DevicePolicy from the device's factory (tools/servo's
/// makeDevicePolicy, which the tools and tests that run an experiment hand in: this library knows
/// no device registry) and its board's spec (joints, sensor resolution, servo rate).
struct DeviceProduct {
  std::function<std::unique_ptr<DevicePolicy>()> make_policy;
  BoardSpec spec;
};

class PolicyServo {
 public:
  /// policy: kept by reference (it must outlive this); spec: the board's joint and actuator counts,
  /// sensor resolution and servo rate. Throws Error for counts beyond the wire protocol's channels.
  PolicyServo(DevicePolicy& policy, const BoardSpec& spec);

  /// Set-up: a new session whose efforts act command_delay periods after the reading they answer
  /// (throws like DevicePolicy::reset).
  void reset(int command_delay);
  /// One reading: positions [rad or m] as the sensors give them; applied_age: the command the board
  /// names as applied over the period the reading ends (DevicePolicy::commandApplied), -1: none.
  /// Returns what the scene sees.
  const SensedState& sense(const double* positions, int applied_age = -1) noexcept;
  /// The scene's force [N] (device frame) computed from sense()'s state -> the actuators' efforts. A
  /// fault or a non-finite effort sends zero and is counted.
  Fault render(const Vec3& force, double* efforts) noexcept;

  std::uint64_t faults() const noexcept { return faults_; }
  const SensedState& state() const noexcept { return state_; }
  DevicePolicy& policy() noexcept { return policy_; }

 private:
  DevicePolicy& policy_;
  const int joints_, actuators_;
  const double dt_;
  JointRateEstimator rate_;
  std::array<double, wire::kMaxChannels> rates_{};
  SensedState state_;
  bool first_ = true;
  std::uint64_t ticks_ = 0;
  std::uint64_t faults_ = 0;
};

}  // namespace uhaptics::experiments
