// The CHAI3D device class the registry (plugin/chai3d/src/device_registry.cpp) creates for this device.
#include "uhaptics/chai3d/CTauDevice.hpp"

namespace uhaptics::devices::tau {

chai3d::cUhapticsDevicePtr createChai3dDevice(const DeviceSelection& selection, unsigned int device_number) {
  return chai3d::cTauDevice::create(selection, device_number);
}

}  // namespace uhaptics::devices::tau
