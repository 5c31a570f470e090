// The RHI's CHAI3D device class, and the function the registry (plugin/chai3d/src/device_registry.cpp)
// creates it with.
#include "uhaptics/chai3d/CRedundantPlanarDevice.hpp"

#include "uhaptics/backends/device_definition.hpp"

namespace uhaptics::devices::rhi {
DeviceDefinition definition();  // backend/src/rhi_definition.cpp
}  // namespace uhaptics::devices::rhi

namespace chai3d {

// Assumed: a 10 cm disc around home keeps the arm far from its 0.786 m reach.
cRedundantPlanarDevice::cRedundantPlanarDevice(unsigned int a_deviceNumber, const uhaptics::DeviceSelection& a_selection)
    : cPlanarLinkageDevice<4>(a_deviceNumber, a_selection,
                              Model::load(paramsDirectory() + "/" + uhaptics::devices::rhi::definition().params_file, "rhi4"),
                              "4-DoF planar redundant interface", 0.1) {}

}  // namespace chai3d

namespace uhaptics::devices::rhi {

chai3d::cUhapticsDevicePtr createChai3dDevice(const DeviceSelection& selection, unsigned int device_number) {
  return chai3d::cRedundantPlanarDevice::create(selection, device_number);
}

}  // namespace uhaptics::devices::rhi
