#pragma once
// Which device and backend a CHAI3D application gets, chosen without touching its code: from the
// environment, optionally from a JSON file, environment winning.
//
//   UHAPTICS_DEVICE   device name (e.g. exo, tau, rhi); required unless the config file names one
//   UHAPTICS_BACKEND  sim (default), emulated (the in-process board emulator over the wire protocol)
//                     or usb (the device's board over libusb)
//   UHAPTICS_CONFIG   path of a JSON file (format below)
//   UHAPTICS_STATS    where the device writes its session statistics (default: none)
//   UHAPTICS_HAND     on (default with sim) / off: the scripted hand that moves the simulated device
//   UHAPTICS_RECORD   where the device writes the scripted hand's side of the session, a hand
//                     recording (docs/recording.md); needs the scripted hand (sim or emulated)
//   UHAPTICS_HAND_RECORDING  a hand recording the scripted hand follows instead of its waypoints,
//                     grip and force limit
//
// Config file ("device": "chai3d-selection", "format_version": 1):
//   {"selection": {"device": "tau", "backend": "sim"}, "stats": "/tmp/tau.json",
//    "record": "/tmp/tau-hand.csv",
//    "hand": {"enabled": 1, "lap_time": 4, "stiffness": 150, "damping": 4, "max_force": 8,
//             "waypoint_count": 2, "waypoints": [0,0,0.5, 0,0,-0.3], "recording": "hand.csv"},
//    "options": {"<device>": {"<option>": value, ...}}}  (device-specific renderer options)
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "uhaptics/backends/joint_io.hpp"
#include "uhaptics/backends/scripted_hand.hpp"
#include "uhaptics/models/param_file.hpp"

namespace uhaptics {

struct DeviceSelection {
  std::string device;
  std::string backend = "sim";
  std::string stats_path;        // empty: no stats file
  std::string record_path;       // empty: no hand recording
  bool hand_enabled = true;      // only meaningful with the sim backend
  ScriptedHandOptions hand;
  /// The configuration named the hand's waypoints or a recording (a path chosen for a scene).
  /// Position-driven devices (the exoskeleton's finger) then follow it instead of their own default
  /// motion, repeating it every hand.lap_time (a recording's duration when it names one).
  bool hand_path_given = false;
  std::optional<ParamFile> config;  // for device-specific options ("options/<device>/<name>")
  std::map<std::string, double> options;  // device options set in code; win over the config file
  /// Set in code only: receives the joint I/O the backend made (not yet open) and returns the one
  /// the device uses, e.g. a wrapper that records, replays, injects faults or holds the plant still
  /// (the CHAI3D tick benchmark). Empty: the backend's own.
  std::function<std::unique_ptr<JointIo>(std::unique_ptr<JointIo>)> wrap_joint_io;
  /// Set in code only: the joint-I/O options the device is opened with on the emulated and usb
  /// backends: servo settings (rate and board watchdog 0 = the parameter file's) and, emulated only,
  /// emulator_control to inject board faults mid-session. params_dir empty = the default folder;
  /// renderer must stay empty (the device renders in its own ticks).
  JointIoOptions joint_io;

  /// A device option (options map, else config file, else fallback); validated against [lo, hi].
  double option(const std::string& name, double fallback, double lo, double hi) const;
};

/// Environment lookup, injectable for tests (std::getenv semantics: nullptr when unset).
using EnvironmentLookup = std::function<const char*(const char*)>;

/// Reads and validates the selection. Throws uhaptics::Error whose message names the variable or
/// file field, the value, and the valid choices. devices/backends: what this build offers.
DeviceSelection readDeviceSelection(const std::vector<std::string>& devices,
                                    const std::vector<std::string>& backends,
                                    const EnvironmentLookup& environment);

}  // namespace uhaptics
