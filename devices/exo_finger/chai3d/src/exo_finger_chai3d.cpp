// The CHAI3D device class the registry (plugin/chai3d/src/device_registry.cpp) creates for this device.
#include "uhaptics/chai3d/CExoFingerDevice.hpp"

namespace uhaptics::devices::exo_finger {

chai3d::cUhapticsDevicePtr createChai3dDevice(const DeviceSelection& selection, unsigned int device_number) {
  return chai3d::cExoFingerDevice::create(selection, device_number);
}

}  // namespace uhaptics::devices::exo_finger
