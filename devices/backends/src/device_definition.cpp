#include "uhaptics/backends/device_definition.hpp"

#include "uhaptics/core/fault.hpp"
#include "uhaptics/device_list.hpp"  // generated from devices/CMakeLists.txt's registrations

// Each registered device's folder defines uhaptics::devices::<id>::definition().
#define UHAPTICS_DECLARE_DEVICE(id, name) \
  namespace uhaptics::devices::id {       \
  DeviceDefinition definition();          \
  }
UHAPTICS_FOR_EACH_DEVICE(UHAPTICS_DECLARE_DEVICE)
#undef UHAPTICS_DECLARE_DEVICE

namespace uhaptics {
namespace {

std::vector<DeviceDefinition> registered() {
  std::vector<DeviceDefinition> all;
#define UHAPTICS_ADD_DEVICE(id, device_name) \
  all.push_back(devices::id::definition());  \
  all.back().name = device_name;
  UHAPTICS_FOR_EACH_DEVICE(UHAPTICS_ADD_DEVICE)
#undef UHAPTICS_ADD_DEVICE
  for (std::size_t i = 0; i < all.size(); ++i) {
    const DeviceDefinition& d = all[i];
    if (d.wire_code == 0 || d.wire_code > wire::kMaxDeviceCode || !d.describe_board || !d.make_plant ||
        d.title.empty() || d.params_file.empty() || d.paper.id.empty() || d.paper.title.empty())
      throw Error("device '" + d.name + "': incomplete definition (wire code 1.." +
                  std::to_string(wire::kMaxDeviceCode) +
                  ", title, paper id and title, parameter file, board and plant required)");
    for (std::size_t j = 0; j < i; ++j) {
      if (all[j].name == d.name || all[j].wire_code == d.wire_code)
        throw Error("devices '" + all[j].name + "' and '" + d.name + "' share a name or a wire code");
    }
  }
  return all;
}

}  // namespace

const std::vector<const DeviceDefinition*>& deviceDefinitions() {
  static const std::vector<DeviceDefinition> all = registered();
  static const std::vector<const DeviceDefinition*> pointers = [] {
    std::vector<const DeviceDefinition*> p;
    for (const DeviceDefinition& d : all) p.push_back(&d);
    return p;
  }();
  return pointers;
}

std::string deviceNameList() {
  const auto& all = deviceDefinitions();
  std::string out;
  for (std::size_t i = 0; i < all.size(); ++i)
    out += (i == 0 ? "" : i + 1 == all.size() ? " or " : ", ") + all[i]->name;
  return out;
}

const DeviceDefinition* findDeviceByPaper(const std::string& paper_id) {
  for (const DeviceDefinition* d : deviceDefinitions())
    if (d->paper.id == paper_id) return d;
  return nullptr;
}

const DeviceDefinition& findDevice(const std::string& name) {
  for (const DeviceDefinition* d : deviceDefinitions())
    if (d->name == name) return *d;
  throw Error("unknown device '" + name + "': use " + deviceNameList());
}

const DeviceDefinition* findDevice(wire::DeviceType code) {
  for (const DeviceDefinition* d : deviceDefinitions())
    if (d->wire_code == static_cast<std::uint8_t>(code)) return d;
  return nullptr;
}

}  // namespace uhaptics
