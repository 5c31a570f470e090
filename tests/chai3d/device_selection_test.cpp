// Device selection from the environment and a config file: precedence, validation, messages.
#include <catch2/catch.hpp>
#include <cstdio>
#include <fstream>
#include <map>
#include <string>

#include "uhaptics/chai3d/device_selection.hpp"
#include "uhaptics/core/fault.hpp"

using uhaptics::readDeviceSelection;

namespace {

struct FakeEnvironment {
  std::map<std::string, std::string> values;
  uhaptics::EnvironmentLookup lookup() const {
    return [this](const char* name) -> const char* {
      const auto it = values.find(name);
      return it == values.end() ? nullptr : it->second.c_str();
    };
  }
};

const std::vector<std::string> kDevices{"exo", "tau"};
const std::vector<std::string> kBackends{"sim"};

}  // namespace

TEST_CASE("selection from environment variables", "[chai3d][selection]") {
  FakeEnvironment env;
  env.values = {{"UHAPTICS_DEVICE", "tau"}, {"UHAPTICS_STATS", "/tmp/s.json"}};
  const auto s = readDeviceSelection(kDevices, kBackends, env.lookup());
  CHECK(s.device == "tau");
  CHECK(s.backend == "sim");
  CHECK(s.stats_path == "/tmp/s.json");
  CHECK(s.hand_enabled);
  CHECK(s.option("anything", 7.0, 0.0, 10.0) == 7.0);  // no config file: the default
  env.values["UHAPTICS_HAND"] = "off";
  CHECK_FALSE(readDeviceSelection(kDevices, kBackends, env.lookup()).hand_enabled);
}

TEST_CASE("invalid selections name the variable and the valid choices", "[chai3d][selection]") {
  FakeEnvironment env;
  CHECK_THROWS_WITH(readDeviceSelection(kDevices, kBackends, env.lookup()),
                    Catch::Contains("no device selected") && Catch::Contains("exo, tau"));
  env.values = {{"UHAPTICS_DEVICE", "phantom"}};
  CHECK_THROWS_WITH(readDeviceSelection(kDevices, kBackends, env.lookup()),
                    Catch::Contains("UHAPTICS_DEVICE = 'phantom'") && Catch::Contains("exo, tau"));
  env.values = {{"UHAPTICS_DEVICE", "exo"}, {"UHAPTICS_BACKEND", "usb"}};
  CHECK_THROWS_WITH(readDeviceSelection(kDevices, kBackends, env.lookup()),
                    Catch::Contains("UHAPTICS_BACKEND = 'usb'") && Catch::Contains("sim"));
  env.values = {{"UHAPTICS_DEVICE", "exo"}, {"UHAPTICS_HAND", "maybe"}};
  CHECK_THROWS_WITH(readDeviceSelection(kDevices, kBackends, env.lookup()), Catch::Contains("UHAPTICS_HAND"));
  env.values = {{"UHAPTICS_CONFIG", "/nonexistent/selection.json"}};
  CHECK_THROWS_AS(readDeviceSelection(kDevices, kBackends, env.lookup()), uhaptics::Error);
}

TEST_CASE("config file selects, the environment overrides", "[chai3d][selection]") {
  const std::string path = "uhaptics-selection-test.json";
  {
    std::ofstream file(path);
    file << R"({"device": "chai3d-selection", "format_version": 1,
               "selection": {"device": "exo", "backend": "sim"}, "stats": "exo.json",
               "hand": {"lap_time": 3, "stiffness": 90, "waypoint_count": 3,
                        "waypoints": [0,0,0.5, 0,0.2,0, 0,0,-0.2]},
               "options": {"exo": {"coupling_stiffness": 250}}})";
  }
  FakeEnvironment env;
  env.values = {{"UHAPTICS_CONFIG", path}};
  auto s = readDeviceSelection(kDevices, kBackends, env.lookup());
  CHECK(s.device == "exo");
  CHECK(s.stats_path == "exo.json");
  CHECK(s.hand.lap_time == 3.0);
  CHECK(s.hand.stiffness == 90.0);
  REQUIRE(s.hand.waypoints.size() == 3);
  CHECK(s.hand.waypoints[1].y() == 0.2);
  CHECK(s.hand_path_given);
  CHECK_FALSE(readDeviceSelection(kDevices, kBackends, [](const char* a_name) -> const char* {
                return std::string(a_name) == "UHAPTICS_DEVICE" ? "exo" : nullptr;
              }).hand_path_given);  // no file: the device's own default motion
  CHECK(s.option("coupling_stiffness", 1.0, 0.0, 1e4) == 250.0);
  CHECK_THROWS_WITH(s.option("coupling_stiffness", 1.0, 0.0, 100.0), Catch::Contains("coupling_stiffness"));
  s.options["coupling_stiffness"] = 300.0;  // set in code: wins over the file
  CHECK(s.option("coupling_stiffness", 1.0, 0.0, 1e4) == 300.0);
  CHECK_THROWS_WITH(s.option("coupling_stiffness", 1.0, 0.0, 100.0), Catch::Contains("outside"));
  env.values["UHAPTICS_DEVICE"] = "tau";
  s = readDeviceSelection(kDevices, kBackends, env.lookup());
  CHECK(s.device == "tau");
  CHECK(s.option("coupling_stiffness", 1.0, 0.0, 1e4) == 1.0);  // options are per device
  std::remove(path.c_str());
}

TEST_CASE("hand recording options: record and replay, refused where they cannot work", "[chai3d][selection][recording]") {
  const std::string recording = "uhaptics-selection-hand.csv";
  {
    std::ofstream file(recording);
    file << "# uhaptics hand recording\n# format_version: 1\n# workspace_radius_m: 0.025\n"
            "time_s,anchor_x,anchor_y,anchor_z,anchor_vx,anchor_vy,anchor_vz,grip_stiffness_N_per_m,"
            "grip_damping_N_s_per_m,grip_max_force_N,scene_fx_N,scene_fy_N,scene_fz_N,scene_x,scene_y,scene_z\n"
            "0,0,0,0.5,0,0,-0.75,1500,20,12,0,0,0,0,0,0.5\n"
            "0.01,0,0,0.4925,0,0,-0.75,1500,20,12,0,0,0,0,0,0.4925\n";
  }
  FakeEnvironment env;
  env.values = {{"UHAPTICS_DEVICE", "tau"}, {"UHAPTICS_RECORD", "tau-hand.csv"}, {"UHAPTICS_HAND_RECORDING", recording}};
  const auto s = readDeviceSelection(kDevices, kBackends, env.lookup());
  CHECK(s.record_path == "tau-hand.csv");
  REQUIRE(s.hand.recording);
  CHECK(s.hand.recording->samples.size() == 2);
  CHECK(s.hand_path_given);  // a position-driven device follows the recorded hand
  CHECK(s.hand.lap_time == Approx(0.01));  // and repeats the whole recording
  // Recording needs the scripted hand.
  env.values["UHAPTICS_HAND"] = "off";
  CHECK_THROWS_WITH(readDeviceSelection(kDevices, kBackends, env.lookup()),
                    Catch::Contains("UHAPTICS_RECORD = 'tau-hand.csv'") && Catch::Contains("scripted hand"));
  env.values.erase("UHAPTICS_HAND");
  // A malformed recording is refused with its file, line and field.
  {
    std::ofstream file(recording, std::ios::app);
    file << "0.02,0,0,0.485,0,0,-0.75,1500,20,-3,0,0,0,0,0,0.485\n";
  }
  CHECK_THROWS_WITH(readDeviceSelection(kDevices, kBackends, env.lookup()),
                    Catch::Contains(recording + ":7: grip_max_force_N"));
  env.values["UHAPTICS_HAND_RECORDING"] = "/nonexistent/hand.csv";
  CHECK_THROWS_WITH(readDeviceSelection(kDevices, kBackends, env.lookup()),
                    Catch::Contains("/nonexistent/hand.csv: cannot read"));
  std::remove(recording.c_str());
}
