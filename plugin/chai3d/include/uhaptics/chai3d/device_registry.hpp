#pragma once
// The uhaptics devices this build offers to CHAI3D applications, by name, and the factory the
// custom-device slot (and any application that prefers to choose in code) creates them with.
#include <string>
#include <vector>

#include "uhaptics/backends/device_selection.hpp"
#include "uhaptics/chai3d/CUhapticsDevice.hpp"

namespace uhaptics::adapter {

/// Device names accepted in UHAPTICS_DEVICE / selection/device, e.g. "exo".
std::vector<std::string> deviceNames();
/// Backend names accepted in UHAPTICS_BACKEND / selection/backend.
std::vector<std::string> backendNames();
/// A one-line description per device, for messages.
std::string describeDevices();

/// Creates the selected device (not opened). Throws uhaptics::Error when the selection cannot be
/// honoured (unknown device, backend not available for that device, bad options).
chai3d::cUhapticsDevicePtr createDevice(const DeviceSelection& selection, unsigned int device_number = 0);

/// readDeviceSelection() from the process environment, then createDevice().
chai3d::cUhapticsDevicePtr createDeviceFromEnvironment(unsigned int device_number = 0);

}  // namespace uhaptics::adapter
