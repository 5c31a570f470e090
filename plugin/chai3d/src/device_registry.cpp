#include "uhaptics/chai3d/device_registry.hpp"

#include "uhaptics/chai3d/CExoFingerDevice.hpp"
#include "uhaptics/chai3d/CRedundantPlanarDevice.hpp"
#include "uhaptics/chai3d/CTauDevice.hpp"

#include <algorithm>
#include <cstdlib>
#include <functional>

namespace uhaptics::adapter {
namespace {

struct Entry {
  const char* name;
  const char* description;
  std::vector<std::string> backends;
  std::function<chai3d::cUhapticsDevicePtr(const DeviceSelection&, unsigned int)> create;
};

// One line per device class built into the plugin.
const std::vector<Entry>& entries() {
  static const std::vector<Entry> table = {
      {"exo", "finger exoskeleton module, subspace proxy (paper 000)", {"sim", "emulated", "usb"},
       [](const DeviceSelection& s, unsigned int n) -> chai3d::cUhapticsDevicePtr { return chai3d::cExoFingerDevice::create(s, n); }},
      {"tau", "TAU-class 6-DoF parallel device, LQR wall on stiff contact (paper 001)", {"sim", "emulated", "usb"},
       [](const DeviceSelection& s, unsigned int n) -> chai3d::cUhapticsDevicePtr { return chai3d::cTauDevice::create(s, n); }},
      {"rhi", "4-DoF planar redundant interface, J^T F + FME null-space control (paper 003)", {"sim", "emulated", "usb"},
       [](const DeviceSelection& s, unsigned int n) -> chai3d::cUhapticsDevicePtr {
         return chai3d::cRedundantPlanarDevice::create(s, n);
       }},
  };
  return table;
}

}  // namespace

std::vector<std::string> deviceNames() {
  std::vector<std::string> names;
  for (const Entry& e : entries()) names.emplace_back(e.name);
  return names;
}

std::vector<std::string> backendNames() {
  std::vector<std::string> names;
  for (const Entry& e : entries()) {
    for (const auto& b : e.backends) {
      if (std::find(names.begin(), names.end(), b) == names.end()) names.push_back(b);
    }
  }
  if (names.empty()) names.emplace_back("sim");
  return names;
}

std::string describeDevices() {
  std::string out;
  for (const Entry& e : entries()) out += std::string(out.empty() ? "" : "; ") + e.name + " = " + e.description;
  return out.empty() ? "no uhaptics device is built into this plugin" : out;
}

chai3d::cUhapticsDevicePtr createDevice(const DeviceSelection& selection, unsigned int device_number) {
  for (const Entry& e : entries()) {
    if (selection.device != e.name) continue;
    if (std::find(e.backends.begin(), e.backends.end(), selection.backend) == e.backends.end()) {
      std::string offered;
      for (const auto& b : e.backends) offered += (offered.empty() ? "" : ", ") + b;
      throw Error("device '" + selection.device + "' has no backend '" + selection.backend +
                  "' in this build (available: " + offered + ")");
    }
    return e.create(selection, device_number);
  }
  throw Error("unknown device '" + selection.device + "' (" + describeDevices() + ")");
}

chai3d::cUhapticsDevicePtr createDeviceFromEnvironment(unsigned int device_number) {
  const DeviceSelection selection =
      readDeviceSelection(deviceNames(), backendNames(), [](const char* name) { return std::getenv(name); });
  return createDevice(selection, device_number);
}

}  // namespace uhaptics::adapter
