#include "uhaptics/chai3d/device_selection.hpp"

#include <algorithm>

#include "uhaptics/core/fault.hpp"

namespace uhaptics {
namespace {

std::string joined(const std::vector<std::string>& names) {
  if (names.empty()) return "(none built into this plugin)";
  std::string out;
  for (const auto& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

void requireOneOf(const std::string& value, const std::vector<std::string>& choices,
                  const std::string& where, const std::string& what) {
  if (std::find(choices.begin(), choices.end(), value) == choices.end()) {
    throw Error(where + " = '" + value + "' is not a " + what + " of this build; choose one of: " +
                joined(choices));
  }
}

bool parseSwitch(const std::string& value, const std::string& where) {
  if (value == "on" || value == "1" || value == "yes" || value == "true") return true;
  if (value == "off" || value == "0" || value == "no" || value == "false") return false;
  throw Error(where + " = '" + value + "' must be on or off");
}

void followRecording(const std::string& path, ScriptedHandOptions& hand, bool& path_given) {
  if (path.empty()) throw Error("the hand recording's path is empty");
  hand.recording = std::make_shared<const HandRecording>(readHandRecording(path));
  // A position-driven device repeats the hand's path every lap: the recording is one lap.
  hand.lap_time = hand.recording->duration();
  path_given = true;
}

void readHand(const ParamFile& config, ScriptedHandOptions& hand, bool& enabled, bool& path_given) {
  if (config.has("hand/enabled")) enabled = config.integer("hand/enabled", 0, 1) != 0;
  hand.lap_time = config.numberOr("hand/lap_time", hand.lap_time, 0.1, 3600.0);
  hand.stiffness = config.numberOr("hand/stiffness", hand.stiffness, 1.0, 5000.0);
  hand.damping = config.numberOr("hand/damping", hand.damping, 0.0, 500.0);
  hand.max_force = config.numberOr("hand/max_force", hand.max_force, 0.01, 100.0);
  if (config.has("hand/waypoints")) {
    const auto n = static_cast<std::size_t>(config.integer("hand/waypoint_count", 2, 1000));
    const auto flat = config.numbers("hand/waypoints", 3 * n, -2.0, 2.0);
    hand.waypoints.clear();
    for (std::size_t i = 0; i < n; ++i) hand.waypoints.emplace_back(flat[3 * i], flat[3 * i + 1], flat[3 * i + 2]);
    path_given = true;
  }
  if (config.has("hand/recording")) followRecording(config.text("hand/recording"), hand, path_given);
}

}  // namespace

double DeviceSelection::option(const std::string& name, double fallback, double lo, double hi) const {
  if (const auto it = options.find(name); it != options.end()) {
    if (!(it->second >= lo && it->second <= hi)) {
      throw Error("device option " + device + "/" + name + " = " + std::to_string(it->second) + " is outside [" +
                  std::to_string(lo) + ", " + std::to_string(hi) + "]");
    }
    return it->second;
  }
  if (!config) return fallback;
  return config->numberOr("options/" + device + "/" + name, fallback, lo, hi);
}

DeviceSelection readDeviceSelection(const std::vector<std::string>& devices,
                                    const std::vector<std::string>& backends,
                                    const EnvironmentLookup& environment) {
  DeviceSelection selection;
  const auto env = [&](const char* name) -> std::optional<std::string> {
    const char* value = environment(name);
    if (value == nullptr || *value == '\0') return std::nullopt;
    return std::string(value);
  };

  if (const auto path = env("UHAPTICS_CONFIG")) {
    selection.config = ParamFile::load(*path);
    const ParamFile& config = *selection.config;
    config.requireFormat("chai3d-selection", 1);
    if (config.has("selection/device")) {
      selection.device = config.text("selection/device");
      requireOneOf(selection.device, devices, config.origin() + ": selection/device", "device");
    }
    if (config.has("selection/backend")) {
      selection.backend = config.text("selection/backend");
      requireOneOf(selection.backend, backends, config.origin() + ": selection/backend", "backend");
    }
    if (config.has("stats")) selection.stats_path = config.text("stats");
    if (config.has("record")) selection.record_path = config.text("record");
    readHand(config, selection.hand, selection.hand_enabled, selection.hand_path_given);
    // The device classes read "options/<device>/<name>" when they are made.
    config.rejectUnreadKeys({"options"});
  }
  if (const auto device = env("UHAPTICS_DEVICE")) {
    selection.device = *device;
    requireOneOf(selection.device, devices, "UHAPTICS_DEVICE", "device");
  }
  if (const auto backend = env("UHAPTICS_BACKEND")) {
    selection.backend = *backend;
    requireOneOf(selection.backend, backends, "UHAPTICS_BACKEND", "backend");
  }
  if (const auto stats = env("UHAPTICS_STATS")) selection.stats_path = *stats;
  if (const auto hand = env("UHAPTICS_HAND")) selection.hand_enabled = parseSwitch(*hand, "UHAPTICS_HAND");
  if (const auto record = env("UHAPTICS_RECORD")) selection.record_path = *record;
  if (const auto recording = env("UHAPTICS_HAND_RECORDING")) {
    followRecording(*recording, selection.hand, selection.hand_path_given);
  }
  if (selection.device.empty()) {
    throw Error("no device selected: set UHAPTICS_DEVICE to one of: " + joined(devices) +
                " (or name it in the UHAPTICS_CONFIG file under selection/device)");
  }
  // A real user holds real hardware; the scripted hand moves the simulated and the emulated device.
  if (selection.backend == "usb") selection.hand_enabled = false;
  if (!selection.record_path.empty() && !selection.hand_enabled) {
    throw Error("UHAPTICS_RECORD = '" + selection.record_path + "': a hand recording records the scripted hand, which is "
                "off (backend " + selection.backend + (selection.backend == "usb" ? ")" : ", UHAPTICS_HAND off)"));
  }
  return selection;
}

}  // namespace uhaptics
