#pragma once
// The controller boards of the three uhaptics devices, as the host sees them: channel counts, effort
// limits and USB identity. These are the defaults until a device's parameter file carries a "usb"
// section (DeviceDescriptor::fromParams reads it then); the numbers are DESIGN.md's:
//   finger exoskeleton: 1 linear actuator (Actuonix L16 class, about 50 N peak) + the sensed joint q_B
//   TAU: 6 revolute actuators, 2 N m saturation
//   RHI planar: 4 revolute actuators, [3, 3, 1, 1] N m
// USB ids: pid.codes' open-hardware vendor 0x1209 with its test product ids 0x0001..0x0003 (assumed;
// devices/udev/99-uhaptics.rules lists the same pairs).
#include <string>

#include "uhaptics/backends/device_descriptor.hpp"

namespace uhaptics {

struct BoardDefaults {
  DeviceDescriptor descriptor;
  double servo_rate_hz;     // host <-> board exchange rate (the exoskeleton's USB runs at 500 Hz)
  double sample_rate_hz;    // board sensor sampling
};

/// Defaults for a device type; throws Error for kTestPlant.
BoardDefaults boardDefaults(wire::DeviceType type);
/// "exo", "tau" or "rhi" -> device type; throws Error naming the accepted names otherwise.
wire::DeviceType deviceTypeFromName(const std::string& name);

}  // namespace uhaptics
