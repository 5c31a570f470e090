#pragma once
// chai3d::cPlanarArmDevice: paper 003's 3-DoF planar example arm as a CHAI3D device: three actuated
// joints for a 2-D task, one degree of self-motion, rendered by cPlanarLinkageDevice<3> (J^T F plus
// force-manipulability null-space control; its comment lists the options and renderer figures).
// Model: the "planar3" parameter file (0.25 m links, 0.5 N m per joint, home q0 = [pi/6, -pi/3,
// -3 pi/4]).
#include <memory>

#include "uhaptics/chai3d/CPlanarLinkageDevice.hpp"

namespace chai3d {

class cPlanarArmDevice;
typedef std::shared_ptr<cPlanarArmDevice> cPlanarArmDevicePtr;

class cPlanarArmDevice : public cPlanarLinkageDevice<3> {
 public:
  /// Throws uhaptics::Error when the parameter file or an option is invalid (naming it).
  cPlanarArmDevice(unsigned int a_deviceNumber, const uhaptics::DeviceSelection& a_selection);
  static cPlanarArmDevicePtr create(const uhaptics::DeviceSelection& a_selection, unsigned int a_deviceNumber = 0) {
    return std::make_shared<cPlanarArmDevice>(a_deviceNumber, a_selection);
  }
};

}  // namespace chai3d
