#include "uhaptics/protocol/device_descriptor.hpp"

#include <cmath>

#include "uhaptics/core/fault.hpp"
#include "uhaptics/models/param_file.hpp"

namespace uhaptics {

void DeviceDescriptor::validate() const {
  const std::string who = "device descriptor '" + name + "': ";
  if (joints < 1 || joints > wire::kMaxChannels || actuators < 1 || actuators > wire::kMaxChannels)
    throw Error(who + "joint and actuator counts must be in [1, " + std::to_string(wire::kMaxChannels) +
                "], got " + std::to_string(joints) + " and " + std::to_string(actuators));
  for (int i = 0; i < actuators; ++i)
    if (!std::isfinite(effort_limit[i]) || effort_limit[i] <= 0.0)
      throw Error(who + "effort limit of actuator " + std::to_string(i) + " must be finite and > 0");
  if ((endpoint_in & 0x80) == 0 || (endpoint_out & 0x80) != 0)
    throw Error(who + "endpoint_in must be an IN address (bit 7 set), endpoint_out an OUT address");
  if (protocol_version < wire::kMinProtocolVersion || protocol_version > wire::kMaxProtocolVersion)
    throw Error(who + "protocol_version " + std::to_string(protocol_version) +
                " is not spoken by this build (supports " + std::to_string(wire::kMinProtocolVersion) +
                ".." + std::to_string(wire::kMaxProtocolVersion) + ")");
}

DeviceDescriptor DeviceDescriptor::fromParams(const ParamFile& file, wire::DeviceType type,
                                              const std::string& name, int joints, int actuators,
                                              const double* effort_limits) {
  DeviceDescriptor d;
  d.name = name;
  d.type = type;
  d.vendor_id = static_cast<std::uint16_t>(file.integer("usb/vendor_id", 0x0001, 0xFFFF));
  d.product_id = static_cast<std::uint16_t>(file.integer("usb/product_id", 0x0000, 0xFFFF));
  d.interface_number = static_cast<int>(file.integer("usb/interface", 0, 255));
  d.endpoint_in = static_cast<std::uint8_t>(file.integer("usb/endpoint_in", 0x81, 0x8F));
  d.endpoint_out = static_cast<std::uint8_t>(file.integer("usb/endpoint_out", 0x01, 0x0F));
  d.protocol_version = static_cast<std::uint8_t>(file.integer("usb/protocol_version", 1, 255));
  d.joints = joints;
  d.actuators = actuators;
  for (int i = 0; i < actuators && i < wire::kMaxChannels; ++i) d.effort_limit[i] = effort_limits[i];
  try {
    d.validate();
  } catch (const Error& e) {
    file.fail(e.what());
  }
  return d;
}

}  // namespace uhaptics
