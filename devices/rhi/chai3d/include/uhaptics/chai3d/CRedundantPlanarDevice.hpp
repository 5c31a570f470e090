#pragma once
// chai3d::cRedundantPlanarDevice: the 4-DoF planar redundant haptic interface (RHI) of paper 003 as
// a CHAI3D device: four actuated joints for a 2-D task, two degrees of self-motion, rendered by
// cPlanarLinkageDevice<4> (J^T F plus force-manipulability null-space control; its comment lists
// the options and renderer figures). Model: the "rhi4" parameter file.
#include <memory>

#include "uhaptics/chai3d/CPlanarLinkageDevice.hpp"

namespace chai3d {

class cRedundantPlanarDevice;
typedef std::shared_ptr<cRedundantPlanarDevice> cRedundantPlanarDevicePtr;

class cRedundantPlanarDevice : public cPlanarLinkageDevice<4> {
 public:
  /// Throws uhaptics::Error when the parameter file or an option is invalid (naming it).
  cRedundantPlanarDevice(unsigned int a_deviceNumber, const uhaptics::DeviceSelection& a_selection);
  static cRedundantPlanarDevicePtr create(const uhaptics::DeviceSelection& a_selection, unsigned int a_deviceNumber = 0) {
    return std::make_shared<cRedundantPlanarDevice>(a_deviceNumber, a_selection);
  }
};

}  // namespace chai3d
