// The finger exoskeleton in the servo tool: its policy (paper 000's subspace proxy) under a proxy
// spring that pulls the fingertip to the middle of its range while the finger flexes and extends.
#include "device_servo_renderers.hpp"
#include "uhaptics/renderers/exo_finger_policy.hpp"

namespace uhaptics::devices::exo_finger {

std::unique_ptr<DevicePolicy> makeServoPolicy(const std::string& params_path) {
  return std::make_unique<ExoFingerPolicy>(ExoFingerModel::load(params_path), ExoFingerPolicy::Options{},
                                           FigureRecorder::none());
}

// 100 N/m toward the device frame's origin (the centre of the fingertip's reachable region): a few
// newtons over the flexion cycle, within what the actuator shows.
Vec3 servoScene(const SensedState& state, double) { return -100.0 * state.position; }

}  // namespace uhaptics::devices::exo_finger
