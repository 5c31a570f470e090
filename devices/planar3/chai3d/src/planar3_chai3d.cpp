// The planar arm's CHAI3D device class, and the function the registry
// (plugin/chai3d/src/device_registry.cpp) creates it with.
#include "uhaptics/chai3d/CPlanarArmDevice.hpp"

#include "uhaptics/backends/device_definition.hpp"

namespace uhaptics::devices::planar3 {
DeviceDefinition definition();  // backend/src/planar3_definition.cpp
}  // namespace uhaptics::devices::planar3

namespace chai3d {

// Assumed: a 5 cm disc around home; the end effector starts 0.2 m from the base, the reach is 0.75 m.
cPlanarArmDevice::cPlanarArmDevice(unsigned int a_deviceNumber, const uhaptics::DeviceSelection& a_selection)
    : cPlanarLinkageDevice<3>(a_deviceNumber, a_selection,
                              Model::load(paramsDirectory() + "/" + uhaptics::devices::planar3::definition().params_file, "planar3"),
                              "3-DoF planar arm", 0.05) {}

}  // namespace chai3d

namespace uhaptics::devices::planar3 {

chai3d::cUhapticsDevicePtr createChai3dDevice(const DeviceSelection& selection, unsigned int device_number) {
  return chai3d::cPlanarArmDevice::create(selection, device_number);
}

}  // namespace uhaptics::devices::planar3
