// The RHI's renderer in the servo thread: the FME null-space controller (paper 003) with a slow
// task force along paper 003's palpation axis u.
#include "planar_fme_servo_renderer.hpp"

namespace uhaptics::devices::rhi {

std::unique_ptr<DeviceServoRenderer> makeServoRenderer(const std::string& params_path) {
  return std::make_unique<PlanarFmeServoRenderer<4>>(Rhi4Model::load(params_path, "rhi4"));
}

}  // namespace uhaptics::devices::rhi
