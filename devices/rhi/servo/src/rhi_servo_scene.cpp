// The RHI in the servo tool: its policy (paper 003's FME null-space control) under the planar
// palpation scene.
#include "device_servo_renderers.hpp"
#include "uhaptics/renderers/planar_fme_policy.hpp"

namespace uhaptics::devices::rhi {

std::unique_ptr<DevicePolicy> makeServoPolicy(const std::string& params_path) {
  using Policy = PlanarFmePolicy<4>;
  return std::make_unique<Policy>(Rhi4Model::load(params_path, "rhi4"), Policy::defaultOptions(), FigureRecorder::none());
}

Vec3 servoScene(const SensedState& state, double time) { return planarPalpationScene(state, time); }

}  // namespace uhaptics::devices::rhi
