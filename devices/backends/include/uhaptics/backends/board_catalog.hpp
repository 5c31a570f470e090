#pragma once
// A device's controller board as the host sees it, from the device's parameter file
// (devices/<folder>/params/<file>.json): channel counts and effort limits from the model (through
// the device's definition) and the link from its "usb" section: vendor/product id (pid.codes' test
// pair 1209:0001-0003, assumed; the build makes the udev rules from the same ids), interface,
// endpoints, protocol version, host exchange rate, board sampling rate and board watchdog timeout.
#include <string>

#include "uhaptics/backends/device_definition.hpp"

namespace uhaptics {

/// Loads <params_dir>/<device.params_file>: the model (counts, limits) and the "usb" section, all
/// validated; throws Error naming the file and field when anything is missing or out of range.
BoardSpec boardSpec(const DeviceDefinition& device, const std::string& params_dir);
/// Same, from a given file (e.g. a lab's copy with its own USB ids).
BoardSpec boardSpecFromFile(const DeviceDefinition& device, const std::string& path);
/// Same, from a parsed file (params_path is the file's origin); every key of it must be read by the
/// model or the board, or it throws Error naming the key and the nearest known one.
BoardSpec boardSpecFromParams(const DeviceDefinition& device, const ParamFile& file);
/// For describe_board: a rate stated twice (the model's own and the usb section's) must agree;
/// fails through the file (naming it and the key) otherwise.
void requireSameRate(const ParamFile& file, const char* key, double usb_value, double model_value);

}  // namespace uhaptics
