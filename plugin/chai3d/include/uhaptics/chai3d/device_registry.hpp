#pragma once
// The uhaptics devices this build offers to CHAI3D applications, by name, and the factory the
// custom-device slot (and any application that prefers to choose in code) creates them with.
#include <string>
#include <vector>

#include "uhaptics/chai3d/device_selection.hpp"
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

// ---- CHAI3D's custom-device slot -------------------------------------------------------------
// Defined by the slot itself (plugin/chai3d/slot/CMyCustomDevice.cpp): only programs that link
// uhaptics::chai3d have them (a program linking only uhaptics::chai3d_adapters fails to link).

/// The uhaptics device behind a device CHAI3D's cHapticDeviceHandler handed out, or nullptr when
/// that device is not a uhaptics one (another make, the slot's unavailable device, CHAI3D's null
/// device, nullptr). A cUhapticsDevice passed in directly is returned as it is. The handler's
/// device is a chai3d::cMyCustomDevice, not the uhaptics device itself, so a dynamic_cast of it
/// finds nothing; this does. Cast the result to the device class for its own functions, e.g.
///   cGenericHapticDevicePtr hapticDevice;
///   handler->getDevice(hapticDevice, 0);
///   auto tau = std::dynamic_pointer_cast<chai3d::cTauDevice>(uhaptics::adapter::uhapticsDevice(hapticDevice));
///   if (tau) tau->setWallMode(chai3d::cTauDevice::C_TAU_WALL_LQR);
/// (likewise cAlgorithmLqrWall::install(point, tau), cExoFingerTool::setExoFingerDevice(exo),
/// cRedundantPlanarDevice::setNullSpaceOptions(), getJointAnglesRad(), enableForces()). Both are one
/// device: what either is told, the other reports. Thread-safe.
chai3d::cUhapticsDevicePtr uhapticsDevice(const chai3d::cGenericHapticDevicePtr& device);

/// Makes the slot hand out the device of `selection` to the handlers created from now on, instead
/// of the one the environment (UHAPTICS_DEVICE, ...) names: for applications that choose in code
/// but keep CHAI3D's handler, and for tests. Creates the device now (not opened) and throws
/// uhaptics::Error when the selection cannot be honoured (as createDevice()) or while a device the
/// slot handed out is still alive (destroy the handlers and their devices first); the previous
/// selection then stays.
void selectSlotDevice(const DeviceSelection& selection);

/// Forgets the selection: the next handler reads it from the environment again. Throws
/// uhaptics::Error while a device the slot handed out is still alive.
void resetSlotSelection();

}  // namespace uhaptics::adapter
