#include "uhaptics/backends/board_catalog.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "uhaptics/core/fault.hpp"
#include "uhaptics/models/param_file.hpp"

namespace uhaptics {

void requireSameRate(const ParamFile& file, const char* key, double usb_value, double model_value) {
  if (std::abs(usb_value - model_value) > 1e-9 * std::abs(model_value))
    file.fail(std::string(key) + " = " + std::to_string(usb_value) + " disagrees with the model's " +
              std::to_string(model_value));
}

BoardSpec boardSpec(const DeviceDefinition& device, const std::string& params_dir) {
  return boardSpecFromFile(device, params_dir + "/" + device.params_file);
}

BoardSpec boardSpecFromFile(const DeviceDefinition& device, const std::string& path) {
  BoardSpec b = boardSpecFromParams(device, ParamFile::load(path));
  b.params_path = path;
  return b;
}

BoardSpec boardSpecFromParams(const DeviceDefinition& device, const ParamFile& file) {
  BoardSpec b;
  b.params_path = file.origin();
  b.servo_rate_hz = file.number("usb/servo_rate_hz", 500.0, 10000.0);
  b.sample_rate_hz = file.number("usb/sample_rate_hz", 100.0, 100000.0);
  // The range the protocol's boards accept (PROTOCOL.md, CONFIGURE).
  b.board_watchdog_us = static_cast<std::uint32_t>(file.integer("usb/board_watchdog_us", 1000, 1000000));
  device.describe_board(device, file, b);
  // A file with a stability section rates both delays; one without rates nothing.
  const std::string stability = ParamFile::kStabilitySection;
  if (file.has(stability)) {
    const auto rated = [&file](const std::string& key, RatedStiffness& out) {
      const std::vector<double> v = file.numbers(key, out.size(), 1.0, 1e7);
      std::copy(v.begin(), v.end(), out.begin());
    };
    rated(stability + "/max_linear_stiffness", b.rated_stiffness);
    rated(stability + "/max_linear_stiffness_delayed", b.rated_stiffness_delayed);
    b.max_linear_damping = file.number(stability + "/max_linear_damping", 0.0, 1e4);
    // Only a device that senses its orientation states the damping about the tool.
    const std::string angular = stability + "/max_angular_damping";
    if (file.has(angular)) b.max_angular_damping = file.numberOr(angular, 0.0, 0.0, 1e2);
  }
  // The model and the board have read their parts; anything left is a key nobody knows.
  file.rejectUnreadKeys();
  return b;
}

}  // namespace uhaptics
