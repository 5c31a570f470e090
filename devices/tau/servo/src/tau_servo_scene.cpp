// The TAU in the servo tool: its policy (paper 001's LQR wall on stiff contact) in free space, i.e.
// gravity compensation with the wall's observer running.
#include "device_servo_renderers.hpp"
#include "uhaptics/renderers/tau_policy.hpp"

namespace uhaptics::devices::tau {

std::unique_ptr<DevicePolicy> makeServoPolicy(const std::string& params_path) {
  return std::make_unique<TauPolicy>(TauModel::load(params_path), TauPolicy::Options{}, FigureRecorder::none());
}

Vec3 servoScene(const SensedState&, double) { return Vec3::Zero(); }

}  // namespace uhaptics::devices::tau
