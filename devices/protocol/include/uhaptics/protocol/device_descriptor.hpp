#pragma once
// What the host needs to know about a device's controller board: USB identity, channel counts and
// the effort limits every command is held to. Loaded from the "usb" section of the device's
// parameter file (devices/<folder>/params/*.json); counts and limits come from the device model.
#include <array>
#include <cstdint>
#include <string>

#include "uhaptics/protocol/wire_protocol.hpp"

namespace uhaptics {

class ParamFile;

struct DeviceDescriptor {
  std::string name;                        // for messages, e.g. "TAU"
  wire::DeviceType type = wire::DeviceType::kTestPlant;
  std::uint16_t vendor_id = 0;
  std::uint16_t product_id = 0;
  int interface_number = 0;
  std::uint8_t endpoint_in = 0x81;         // bulk IN (board -> host)
  std::uint8_t endpoint_out = 0x01;        // bulk OUT (host -> board)
  std::uint8_t protocol_version = wire::kProtocolVersion;
  int joints = 0;                          // sensed joints in STATE
  int actuators = 0;                       // efforts in COMMAND
  std::array<double, wire::kMaxChannels> effort_limit{};  // N m or N, > 0

  /// Throws Error when counts or limits are out of range (set-up time check).
  void validate() const;

  /// Reads "usb/vendor_id", "usb/product_id", "usb/interface", "usb/endpoint_in", "usb/endpoint_out",
  /// "usb/protocol_version" from the file; counts and limits are the model's.
  static DeviceDescriptor fromParams(const ParamFile& file, wire::DeviceType type, const std::string& name,
                                     int joints, int actuators, const double* effort_limits);
};

}  // namespace uhaptics
