#include "uhaptics/chai3d/device_registry.hpp"

#include <algorithm>
#include <cstdlib>

#include "uhaptics/backends/device_definition.hpp"
#include "uhaptics/backends/joint_io.hpp"
#include "uhaptics/device_list.hpp"  // generated from devices/CMakeLists.txt's registrations

// Each registered device's folder defines uhaptics::devices::<id>::createChai3dDevice().
#define UHAPTICS_DECLARE_CHAI3D_DEVICE(id, name)                                                           \
  namespace uhaptics::devices::id {                                                                         \
  chai3d::cUhapticsDevicePtr createChai3dDevice(const DeviceSelection& selection, unsigned int device_number); \
  }
UHAPTICS_FOR_EACH_DEVICE(UHAPTICS_DECLARE_CHAI3D_DEVICE)
#undef UHAPTICS_DECLARE_CHAI3D_DEVICE

namespace uhaptics::adapter {

std::vector<std::string> deviceNames() {
  std::vector<std::string> names;
  for (const DeviceDefinition* d : deviceDefinitions()) names.push_back(d->name);
  return names;
}

std::vector<std::string> backendNames() { return jointIoBackends(); }

std::string describeDevices() {
  std::string out;
  for (const DeviceDefinition* d : deviceDefinitions()) out += (out.empty() ? "" : "; ") + d->name + " = " + d->summary;
  return out.empty() ? "no uhaptics device is built into this plugin" : out;
}

chai3d::cUhapticsDevicePtr createDevice(const DeviceSelection& selection, unsigned int device_number) {
  const std::vector<std::string> backends = backendNames();
  if (std::find(backends.begin(), backends.end(), selection.backend) == backends.end()) {
    std::string offered;
    for (const auto& b : backends) offered += (offered.empty() ? "" : ", ") + b;
    throw Error("device '" + selection.device + "' has no backend '" + selection.backend +
                "' in this build (available: " + offered + ")");
  }
#define UHAPTICS_CREATE_CHAI3D_DEVICE(id, registered_name) \
  if (selection.device == registered_name) return devices::id::createChai3dDevice(selection, device_number);
  UHAPTICS_FOR_EACH_DEVICE(UHAPTICS_CREATE_CHAI3D_DEVICE)
#undef UHAPTICS_CREATE_CHAI3D_DEVICE
  throw Error("unknown device '" + selection.device + "' (" + describeDevices() + ")");
}

chai3d::cUhapticsDevicePtr createDeviceFromEnvironment(unsigned int device_number) {
  const DeviceSelection selection =
      readDeviceSelection(deviceNames(), backendNames(), [](const char* name) { return std::getenv(name); });
  return createDevice(selection, device_number);
}

}  // namespace uhaptics::adapter
