// Paper 003's planar arm in the servo tool: its policy (FME null-space control) under the planar
// palpation scene.
#include "device_servo_renderers.hpp"
#include "uhaptics/renderers/planar_fme_policy.hpp"

namespace uhaptics::devices::planar3 {

std::unique_ptr<DevicePolicy> makeServoPolicy(const std::string& params_path) {
  using Policy = PlanarFmePolicy<3>;
  return std::make_unique<Policy>(Planar3Model::load(params_path, "planar3"), Policy::defaultOptions(), FigureRecorder::none());
}

Vec3 servoScene(const SensedState& state, double time) { return planarPalpationScene(state, time); }

}  // namespace uhaptics::devices::planar3
