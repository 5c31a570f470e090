#include "device_servo_renderers.hpp"

#include "uhaptics/core/fault.hpp"
#include "uhaptics/device_list.hpp"  // generated from devices/CMakeLists.txt's registrations

// Each registered device's folder defines uhaptics::devices::<id>::makeServoRenderer().
#define UHAPTICS_DECLARE_RENDERER(id, name)                                                  \
  namespace uhaptics::devices::id {                                                          \
  std::unique_ptr<DeviceServoRenderer> makeServoRenderer(const std::string& params_path); \
  }
UHAPTICS_FOR_EACH_DEVICE(UHAPTICS_DECLARE_RENDERER)
#undef UHAPTICS_DECLARE_RENDERER

namespace uhaptics {

std::unique_ptr<DeviceServoRenderer> makeDeviceRenderer(const DeviceDefinition& device, const std::string& params_dir) {
  const std::string path = params_dir + "/" + device.params_file;
#define UHAPTICS_MAKE_RENDERER(id, registered_name) \
  if (device.name == registered_name) return devices::id::makeServoRenderer(path);
  UHAPTICS_FOR_EACH_DEVICE(UHAPTICS_MAKE_RENDERER)
#undef UHAPTICS_MAKE_RENDERER
  throw Error("makeDeviceRenderer: device '" + device.name + "' is not registered");
}

}  // namespace uhaptics
