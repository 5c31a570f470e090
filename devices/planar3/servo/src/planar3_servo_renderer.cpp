// The planar arm's renderer in the servo thread: the FME null-space controller (paper 003) with a
// slow task force along the palpation axis u.
#include "planar_fme_servo_renderer.hpp"

namespace uhaptics::devices::planar3 {

std::unique_ptr<DeviceServoRenderer> makeServoRenderer(const std::string& params_path) {
  return std::make_unique<PlanarFmeServoRenderer<3>>(Planar3Model::load(params_path, "planar3"));
}

}  // namespace uhaptics::devices::planar3
