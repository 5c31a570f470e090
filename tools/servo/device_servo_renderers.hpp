#pragma once
// Each device's rendering policy (uhaptics::DevicePolicy, the object the CHAI3D adapter runs) as a
// ServoRenderer in the servo thread, with a scripted scene in place of an application, so the servo
// tool and the end-to-end tests run what an application runs: policy -> safety stage -> wire
// protocol -> board (emulated: the device's simulation). Each device's folder
// (devices/<device>/servo/) makes its policy with its defaults and says what its scene asks for:
//
//   finger exoskeleton: a proxy spring pulling the fingertip to the middle of its range while the
//                       finger flexes and extends (as in paper 000's Fig. 4)
//   TAU:                free space: gravity compensation, the LQR wall's observer running
//   planar linkages:    a slow task force along paper 003's palpation axis u, 2 N at 0.5 Hz
//
// Rates come from the shared estimator over the board's sample clock, as in the adapter. The
// graphics thread's effort request is added to the policy's output (how a test pushes a command past
// the limits to see the safety stage act on it). render() never allocates or throws.
#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>

#include "uhaptics/backends/device_definition.hpp"
#include "uhaptics/backends/joint_io.hpp"
#include "uhaptics/backends/servo_loop.hpp"
#include "uhaptics/renderers/device_policy.hpp"

namespace uhaptics {

/// What a scripted scene asks of a period: the force on the tool [N], device frame, from what the
/// policy sensed and the time [s].
using ScriptedScene = Vec3 (*)(const SensedState& state, double time);

class DeviceServoRenderer final : public ServoRenderer {
 public:
  /// policy: reset here for the board protocol's command delay; spec: the board's joint count, sensor
  /// resolution and servo rate.
  DeviceServoRenderer(std::unique_ptr<DevicePolicy> policy, ScriptedScene scene, const BoardSpec& spec);

  void render(const DeviceSnapshot& snapshot, const EffortRequest& request, double* efforts) noexcept override;
  void noReading(const DeviceSnapshot& snapshot) noexcept override;
  /// Periods whose policy returned a fault or a non-finite effort (written by the servo thread: read
  /// it after stop()).
  std::uint64_t faults() const noexcept { return faults_; }
  const DevicePolicy& policy() const noexcept { return *policy_; }

 private:
  std::unique_ptr<DevicePolicy> policy_;
  ScriptedScene scene_;
  const int joints_, actuators_;
  const double dt_;
  JointRateEstimator rate_;
  std::array<double, wire::kMaxChannels> rates_{};
  SensedState state_;
  bool first_ = true;
  std::uint64_t ticks_ = 0;
  std::uint64_t faults_ = 0;
};

/// The planar linkages' scene: a slow task force along paper 003's palpation axis u (task y), 2 N at
/// 0.5 Hz.
inline Vec3 planarPalpationScene(const SensedState&, double time) {
  return planarToDevice(Vec2(0.0, 2.0 * std::sin(2.0 * M_PI * 0.5 * time)));
}

/// The device's policy and scene on the model in <params_dir>/<its parameter file>; throws Error for
/// a malformed file.
std::unique_ptr<DeviceServoRenderer> makeDeviceRenderer(const DeviceDefinition& device, const std::string& params_dir);
/// The device's policy alone (as makeDeviceRenderer makes it, without the scene), for callers that
/// run it under their own loop (the Z-width harness: the policy in free space); throws as above.
std::unique_ptr<DevicePolicy> makeDevicePolicy(const DeviceDefinition& device, const std::string& params_dir);

}  // namespace uhaptics
