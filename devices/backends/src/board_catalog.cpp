#include "uhaptics/backends/board_catalog.hpp"

#include <array>
#include <cmath>

#include "uhaptics/core/fault.hpp"
#include "uhaptics/models/exo_finger_model.hpp"
#include "uhaptics/models/param_file.hpp"
#include "uhaptics/models/planar_linkage_model.hpp"
#include "uhaptics/models/tau_model.hpp"

namespace uhaptics {
namespace {

// A rate stated twice (the model's own and the usb section's) must agree.
void requireSame(const ParamFile& file, const char* key, double usb_value, double model_value) {
  if (std::abs(usb_value - model_value) > 1e-9 * std::abs(model_value))
    file.fail(std::string(key) + " = " + std::to_string(usb_value) + " disagrees with the model's " +
              std::to_string(model_value));
}

}  // namespace

std::string paramsFileName(wire::DeviceType type) {
  switch (type) {
    case wire::DeviceType::kExoFinger: return "exo_finger.json";
    case wire::DeviceType::kTau: return "tau.json";
    case wire::DeviceType::kRhiPlanar: return "rhi4.json";
    case wire::DeviceType::kTestPlant: break;
  }
  throw Error("the test plant has no board and no parameter file");
}

BoardSpec boardSpec(wire::DeviceType type, const std::string& params_dir) {
  return boardSpecFromFile(type, params_dir + "/" + paramsFileName(type));
}

BoardSpec boardSpecFromFile(wire::DeviceType type, const std::string& path) {
  const ParamFile file = ParamFile::load(path);
  BoardSpec b;
  b.params_path = path;
  b.servo_rate_hz = file.number("usb/servo_rate_hz", 500.0, 10000.0);
  b.sample_rate_hz = file.number("usb/sample_rate_hz", 100.0, 100000.0);
  // The range the protocol's boards accept (PROTOCOL.md, CONFIGURE).
  b.board_watchdog_us = static_cast<std::uint32_t>(file.integer("usb/board_watchdog_us", 1000, 1000000));
  std::array<double, wire::kMaxChannels> limits{};
  switch (type) {
    case wire::DeviceType::kExoFinger: {
      const ExoFingerModel model = ExoFingerModel::fromParams(file);
      requireSame(file, "usb/servo_rate_hz", b.servo_rate_hz, model.hostRateHz());
      requireSame(file, "usb/sample_rate_hz", b.sample_rate_hz, model.boardRateHz());
      limits[0] = model.forceLimit()(0);
      b.descriptor = DeviceDescriptor::fromParams(file, type, "finger exoskeleton", ExoFingerModel::kJoints,
                                                  ExoFingerModel::kActuated, limits.data());
      break;
    }
    case wire::DeviceType::kTau: {
      const TauModel model = TauModel::fromParams(file);
      requireSame(file, "usb/servo_rate_hz", b.servo_rate_hz, 1.0 / model.servoPeriod());
      for (int i = 0; i < 6; ++i) limits[i] = model.torqueLimit()(i);
      b.descriptor = DeviceDescriptor::fromParams(file, type, "TAU", 6, 6, limits.data());
      break;
    }
    case wire::DeviceType::kRhiPlanar: {
      const Rhi4Model model = Rhi4Model::fromFile(path, "rhi4");
      for (int i = 0; i < 4; ++i) limits[i] = model.torqueLimits()(i);
      b.descriptor = DeviceDescriptor::fromParams(file, type, "RHI planar", 4, 4, limits.data());
      break;
    }
    case wire::DeviceType::kTestPlant:
      throw Error("boardSpec: the test plant has no board");
  }
  return b;
}

wire::DeviceType deviceTypeFromName(const std::string& name) {
  if (name == "exo") return wire::DeviceType::kExoFinger;
  if (name == "tau") return wire::DeviceType::kTau;
  if (name == "rhi") return wire::DeviceType::kRhiPlanar;
  throw Error("unknown device '" + name + "': use exo, tau or rhi");
}

}  // namespace uhaptics
