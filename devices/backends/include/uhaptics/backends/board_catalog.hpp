#pragma once
// The controller boards of the three uhaptics devices, as the host sees them. Everything comes from
// the device's parameter file (devices/params/<file>.json): channel counts and effort limits from
// the model (exoskeleton: 1 linear actuator, limits/force_limit; TAU: 6 joints, 2 N m; RHI: 4 joints,
// [3, 3, 1, 1] N m) and the link from its "usb" section: vendor/product id (pid.codes' test pair
// 1209:0001-0003, assumed; devices/udev/99-uhaptics.rules lists the same), interface, endpoints,
// protocol version, host exchange rate, board sampling rate and board watchdog timeout.
#include <cstdint>
#include <string>

#include "uhaptics/protocol/device_descriptor.hpp"

namespace uhaptics {

class ParamFile;

struct BoardSpec {
  DeviceDescriptor descriptor;
  double servo_rate_hz = 0.0;         // host <-> board exchange rate (the exoskeleton's USB: 500 Hz)
  double sample_rate_hz = 0.0;        // board sensor sampling
  std::uint32_t board_watchdog_us = 0;  // what the host configures with CONFIGURE
  std::string params_path;            // the file it came from
};

/// "exo_finger.json", "tau.json" or "rhi4.json"; throws Error for kTestPlant.
std::string paramsFileName(wire::DeviceType type);
/// Loads <params_dir>/<paramsFileName(type)>: the model (counts, limits) and the "usb" section, all
/// validated; throws Error naming the file and field when anything is missing or out of range.
BoardSpec boardSpec(wire::DeviceType type, const std::string& params_dir);
/// Same, from a given file (e.g. a lab's copy with its own USB ids).
BoardSpec boardSpecFromFile(wire::DeviceType type, const std::string& path);
/// "exo", "tau" or "rhi" -> device type; throws Error naming the accepted names otherwise.
wire::DeviceType deviceTypeFromName(const std::string& name);

}  // namespace uhaptics
