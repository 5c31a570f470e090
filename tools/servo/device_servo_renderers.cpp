#include "device_servo_renderers.hpp"

#include <algorithm>
#include <cmath>

#include "uhaptics/backends/board_catalog.hpp"
#include "uhaptics/core/fault.hpp"
#include "uhaptics/device_list.hpp"  // generated from devices/CMakeLists.txt's registrations

// Each registered device's folder defines uhaptics::devices::<id>::makeServoPolicy() and
// servoScene().
#define UHAPTICS_DECLARE_RENDERER(id, name)                                                  \
  namespace uhaptics::devices::id {                                                          \
  std::unique_ptr<DevicePolicy> makeServoPolicy(const std::string& params_path);             \
  Vec3 servoScene(const SensedState& state, double time);                                    \
  }
UHAPTICS_FOR_EACH_DEVICE(UHAPTICS_DECLARE_RENDERER)
#undef UHAPTICS_DECLARE_RENDERER

namespace uhaptics {

DeviceServoRenderer::DeviceServoRenderer(std::unique_ptr<DevicePolicy> policy, ScriptedScene scene, const BoardSpec& spec)
    : policy_(std::move(policy)),
      scene_(scene),
      joints_(spec.descriptor.joints),
      actuators_(spec.descriptor.actuators),
      dt_(1.0 / spec.servo_rate_hz) {
  if (!policy_ || scene_ == nullptr) throw Error("DeviceServoRenderer: needs a policy and a scene");
  rate_.setResolution(spec.position_resolution.data(), joints_);
  policy_->reset(ServoLoop::kCommandDelayPeriods);  // its efforts act a period after their reading
}

void DeviceServoRenderer::render(const DeviceSnapshot& s, const EffortRequest& request, double* efforts) noexcept {
  if (first_) rate_.reset();
  rate_.update(s.position.data(), joints_, s.sample_time_us[0], rates_.data());
  const Vec3 seen = state_.position;  // what the scene saw before this reading
  policy_->sense(SensedJoints{s.position.data(), rates_.data(), first_}, state_);
  SceneInput input;
  input.time = static_cast<double>(ticks_) * dt_;
  input.dt = dt_;
  input.force = scene_(state_, input.time);
  input.seen_position = first_ ? state_.position : seen;
  first_ = false;
  ++ticks_;
  Fault fault = policy_->render(input, efforts);
  for (int i = 0; i < actuators_; ++i) {
    if (!std::isfinite(efforts[i]) && fault == Fault::kNone) fault = Fault::kNonFiniteResult;
  }
  if (fault != Fault::kNone) {
    ++faults_;
    std::fill(efforts, efforts + actuators_, 0.0);
  }
  for (int i = 0; i < actuators_ && i < request.count; ++i) efforts[i] += request.effort[i];
}

void DeviceServoRenderer::noReading(const DeviceSnapshot&) noexcept { policy_->readingLost(); }

std::unique_ptr<DeviceServoRenderer> makeDeviceRenderer(const DeviceDefinition& device, const std::string& params_dir) {
  const std::string path = params_dir + "/" + device.params_file;
  const BoardSpec spec = boardSpec(device, params_dir);
#define UHAPTICS_MAKE_RENDERER(id, registered_name)                                                      \
  if (device.name == registered_name)                                                                     \
    return std::make_unique<DeviceServoRenderer>(devices::id::makeServoPolicy(path), &devices::id::servoScene, spec);
  UHAPTICS_FOR_EACH_DEVICE(UHAPTICS_MAKE_RENDERER)
#undef UHAPTICS_MAKE_RENDERER
  throw Error("makeDeviceRenderer: device '" + device.name + "' is not registered");
}

std::unique_ptr<DevicePolicy> makeDevicePolicy(const DeviceDefinition& device, const std::string& params_dir) {
  const std::string path = params_dir + "/" + device.params_file;
#define UHAPTICS_MAKE_POLICY(id, registered_name) \
  if (device.name == registered_name) return devices::id::makeServoPolicy(path);
  UHAPTICS_FOR_EACH_DEVICE(UHAPTICS_MAKE_POLICY)
#undef UHAPTICS_MAKE_POLICY
  throw Error("makeDevicePolicy: device '" + device.name + "' is not registered");
}

}  // namespace uhaptics
