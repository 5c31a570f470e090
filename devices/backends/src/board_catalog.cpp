#include "uhaptics/backends/board_catalog.hpp"

#include "uhaptics/core/fault.hpp"

namespace uhaptics {

BoardDefaults boardDefaults(wire::DeviceType type) {
  BoardDefaults b;
  DeviceDescriptor& d = b.descriptor;
  d.type = type;
  d.vendor_id = 0x1209;
  b.sample_rate_hz = 1000.0;
  switch (type) {
    case wire::DeviceType::kExoFinger:
      d.name = "finger exoskeleton";
      d.product_id = 0x0001;
      d.joints = 2;      // actuator stroke l_x and the potentiometer on q_B
      d.actuators = 1;
      d.effort_limit[0] = 50.0;  // N
      b.servo_rate_hz = 500.0;
      break;
    case wire::DeviceType::kTau:
      d.name = "TAU";
      d.product_id = 0x0002;
      d.joints = d.actuators = 6;
      for (int i = 0; i < 6; ++i) d.effort_limit[i] = 2.0;  // N m
      b.servo_rate_hz = 1000.0;
      break;
    case wire::DeviceType::kRhiPlanar:
      d.name = "RHI planar";
      d.product_id = 0x0003;
      d.joints = d.actuators = 4;
      d.effort_limit = {3.0, 3.0, 1.0, 1.0};  // N m
      b.servo_rate_hz = 1000.0;
      break;
    case wire::DeviceType::kTestPlant:
      throw Error("boardDefaults: the test plant has no board");
  }
  d.validate();
  return b;
}

wire::DeviceType deviceTypeFromName(const std::string& name) {
  if (name == "exo") return wire::DeviceType::kExoFinger;
  if (name == "tau") return wire::DeviceType::kTau;
  if (name == "rhi") return wire::DeviceType::kRhiPlanar;
  throw Error("unknown device '" + name + "': use exo, tau or rhi");
}

}  // namespace uhaptics
