// Hand recordings (docs/recording.md): a recorded scripted hand replays the same hand within the
// stated tolerance, the recorder keeps its rows without allocating, and malformed files are refused
// with the file, line and field.
#include <catch2/catch.hpp>
#include <cmath>
#include <memory>
#include <sstream>
#include <string>

#include "uhaptics/backends/hand_recording.hpp"
#include "uhaptics/backends/scripted_hand.hpp"
#include "uhaptics/core/fault.hpp"
#include "uhaptics/tools/alloc_probe.hpp"

using uhaptics::HandRecorder;
using uhaptics::HandRecording;
using uhaptics::HandSample;
using uhaptics::ScriptedHand;
using uhaptics::ScriptedHandOptions;
using uhaptics::Vec3;

namespace {

// 23-tooth's hand on the TAU (examples.json, devices/tau/chai3d/dropin.json): down 1.5 radii and back
// every 4 s, paper 001's push.
ScriptedHandOptions toothHand() {
  ScriptedHandOptions options;
  options.waypoints = {Vec3(0, 0, 0.5), Vec3(0, 0, -1.0)};
  options.lap_time = 4.0;
  options.stiffness = 1500.0;
  options.damping = 20.0;
  options.max_force = 12.0;
  return options;
}

// Records `hand` as the CHAI3D device does: a servo tick every `tick` seconds, a row when one is due.
HandRecording recordHand(const ScriptedHand& hand, double radius, double seconds, double tick, double row_period) {
  HandRecorder recorder(row_period, static_cast<std::size_t>(seconds / row_period) + 10);
  const auto ticks = static_cast<long>(std::lround(seconds / tick));
  for (long k = 0; k <= ticks; ++k) {
    const double t = static_cast<double>(k) * tick;
    if (!recorder.due(t)) continue;
    HandSample row;
    row.time = t;
    hand.anchor(t, row.anchor, row.anchor_velocity);
    row.anchor /= radius;
    row.anchor_velocity /= radius;
    const ScriptedHand::Grip grip = hand.grip(t);
    row.stiffness = grip.stiffness;
    row.damping = grip.damping;
    row.max_force = grip.max_force;
    row.scene_force = Vec3(0.0, 0.0, row.anchor.z() < -0.2 ? 3.5 : 0.0);
    row.scene_position = row.anchor;
    recorder.record(row);
  }
  HandRecording recording;
  recording.workspace_radius = radius;
  recording.device = "tau";
  recording.backend = "sim";
  recording.samples.assign(recorder.rows(), recorder.rows() + recorder.count());
  return recording;
}

HandRecording parseText(const std::string& text) {
  std::istringstream in(text);
  return uhaptics::parseHandRecording(in, "bad.csv");
}

const std::string kHeader =
    "# uhaptics hand recording\n# format_version: 1\n# workspace_radius_m: 0.025\n"
    "time_s,anchor_x,anchor_y,anchor_z,anchor_vx,anchor_vy,anchor_vz,grip_stiffness_N_per_m,"
    "grip_damping_N_s_per_m,grip_max_force_N,scene_fx_N,scene_fy_N,scene_fz_N,scene_x,scene_y,scene_z\n";
const std::string kRow0 = "0,0,0,0.5,0,0,-0.75,1500,20,12,0,0,0,0,0,0.5\n";
const std::string kRow1 = "0.01,0,0,0.4925,0,0,-0.75,1500,20,12,0,0,0,0,0,0.4925\n";

}  // namespace

TEST_CASE("a recorded scripted hand replays the same hand within the stated tolerance", "[backends][recording]") {
  const double radius = 0.025;  // the TAU's
  const double tick = 1e-3, row_period = 0.01, seconds = 8.0;
  const ScriptedHand original(toothHand(), radius, Vec3::Zero());
  const HandRecording written = recordHand(original, radius, seconds, tick, row_period);
  REQUIRE(written.samples.size() == 801);  // 100 rows a second, both ends

  // Through the file format and back.
  ScriptedHandOptions replay_options;
  replay_options.recording = std::make_shared<const HandRecording>(parseText(uhaptics::formatHandRecording(written)));
  CHECK(replay_options.recording->workspace_radius == Approx(radius));
  CHECK(replay_options.recording->device == "tau");
  REQUIRE(replay_options.recording->samples.size() == written.samples.size());
  const ScriptedHand replayed(replay_options, radius, Vec3::Zero());

  // The anchor moves on straight segments at 0.75 radii/s and turns at t = 0 and 2 s (mod 4):
  // between rows interpolation is exact (to the file's 7 digits); within one row period of a turn
  // it cuts the corner by at most speed x period / 2.
  const double speed = 0.75 * radius;
  const double corner_bound = speed * row_period / 2.0;
  double worst_anchor = 0.0, worst_force_off_corner = 0.0;
  for (long k = 0; k <= static_cast<long>(seconds / tick); ++k) {
    const double t = static_cast<double>(k) * tick;
    Vec3 a, va, b, vb;
    original.anchor(t, a, va);
    replayed.anchor(t, b, vb);
    worst_anchor = std::max(worst_anchor, (a - b).norm());
    const double phase = std::fmod(t, 2.0);
    const bool near_corner = phase < row_period || phase > 2.0 - row_period;
    // A tool 1 mm off the anchor, still: the hand's force on it (well below its 12 N limit).
    const Vec3 tool = a + Vec3(0.0, 0.0, 0.001);
    const double error = (original.force(t, tool, Vec3::Zero()) - replayed.force(t, tool, Vec3::Zero())).norm();
    if (!near_corner) worst_force_off_corner = std::max(worst_force_off_corner, error);
    const ScriptedHand::Grip grip = replayed.grip(t);
    REQUIRE(grip.stiffness == Approx(1500.0));
    REQUIRE(grip.max_force == Approx(12.0));
  }
  CHECK(worst_anchor <= corner_bound + 1e-9);
  CHECK(worst_force_off_corner < 1e-3);  // [N]

  // After the recording the hand holds its last anchor, still; the recording scales to the device.
  Vec3 p, v;
  replayed.anchor(100.0, p, v);
  CHECK((p - written.samples.back().anchor * radius).norm() < 1e-9);
  CHECK(v.isZero());
  const ScriptedHand on_larger(replay_options, 2.0 * radius, Vec3::Zero());
  Vec3 q, w;
  replayed.anchor(1.234, p, v);
  on_larger.anchor(1.234, q, w);
  CHECK((q - 2.0 * p).norm() < 1e-12);
  CHECK((w - 2.0 * v).norm() < 1e-12);
}

TEST_CASE("the hand recorder keeps its rate, drops rows when full and allocates nothing", "[backends][recording]") {
  HandRecorder recorder(0.01, 5);
  HandSample row;
  row.stiffness = 100.0;
  row.damping = 1.0;
  row.max_force = 5.0;
  std::size_t recorded = 0;
  {
    const uhaptics::tools::AllocationScope probe;
    for (int k = 0; k < 100; ++k) {
      const double t = k * 1e-3;  // 1 kHz ticks for 0.1 s: rows at 0, 0.01, ... of which 5 fit
      if (!recorder.due(t)) continue;
      row.time = t;
      recorder.record(row);
      ++recorded;
    }
    CHECK(probe.count() == 0);
  }
  CHECK(recorded == 10);
  CHECK(recorder.count() == 5);
  CHECK(recorder.dropped() == 5);
  CHECK(recorder.rows()[4].time == Approx(0.04));
  recorder.clear();
  CHECK(recorder.count() == 0);
  CHECK(recorder.dropped() == 0);
  CHECK(recorder.due(0.0));
  CHECK_THROWS_AS(HandRecorder(0.0, 5), uhaptics::Error);
  CHECK_THROWS_AS(HandRecorder(0.01, 0), uhaptics::Error);
}

TEST_CASE("a replayed hand evaluates without allocating", "[backends][recording]") {
  const double radius = 0.025;
  const ScriptedHand original(toothHand(), radius, Vec3::Zero());
  ScriptedHandOptions options;
  options.recording = std::make_shared<const HandRecording>(recordHand(original, radius, 2.0, 1e-3, 0.01));
  const ScriptedHand replayed(options, radius, Vec3::Zero());
  const uhaptics::tools::AllocationScope probe;
  Vec3 sum = Vec3::Zero();
  for (int k = 0; k < 3000; ++k) sum += replayed.force(k * 1e-3, Vec3::Zero(), Vec3::Zero());
  CHECK(probe.count() == 0);
  CHECK(sum.allFinite());
}

TEST_CASE("malformed hand recordings are refused with the file, line and field", "[backends][recording]") {
  const auto refused = [](const std::string& text, const std::string& where) {
    INFO(text);
    CHECK_THROWS_WITH(parseText(text), Catch::Contains(where));
  };
  CHECK(parseText(kHeader + kRow0 + kRow1).samples.size() == 2);
  refused("", "bad.csv:1: header: the file is empty");
  refused("time_s,anchor_x\n", "bad.csv:1: header");
  refused("# uhaptics hand recording\n# format_version: 2\n", "bad.csv:2: format_version: '2'");
  refused("# uhaptics hand recording\n# workspace_radius_m: 0.025\n" + kHeader.substr(kHeader.find("time_s")),
          "bad.csv:3: format_version: missing");
  refused("# uhaptics hand recording\n# format_version: 1\n# workspace_radius_m: -1\n", "bad.csv:3: workspace_radius_m");
  refused("# uhaptics hand recording\n# format_version: 1\n# workspace_radius_m: 0.025\ntime_s,x\n", "bad.csv:4: columns");
  refused(kHeader + kRow0, "bad.csv:5: rows: a recording needs at least two rows");
  refused(kHeader + kRow0 + "0.01,0,0,0.5,0,0,-0.75,1500,20,12,0,0,0,0,0\n", "bad.csv:6: row: 15 fields");
  refused(kHeader + kRow0 + "0.01,0,0,abc,0,0,-0.75,1500,20,12,0,0,0,0,0,0\n", "bad.csv:6: anchor_z: 'abc' is not a number");
  refused(kHeader + kRow0 + "0.01,0,0,0.5,0,nan,-0.75,1500,20,12,0,0,0,0,0,0\n", "bad.csv:6: anchor_vy: 'nan' is not finite");
  refused(kHeader + kRow0 + "0.01,0,0,0.5,0,0,-0.75,1500,20,12,0,0,,0,0,0\n", "bad.csv:6: scene_fz_N: '' is not a number");
  refused(kHeader + kRow0 + "0,0,0,0.5,0,0,-0.75,1500,20,12,0,0,0,0,0,0\n", "bad.csv:6: time_s: not after");
  refused(kHeader + kRow0 + "0.01,0,0,0.5,0,0,-0.75,9000,20,12,0,0,0,0,0,0\n", "bad.csv:6: grip_stiffness_N_per_m: 9000 is outside");
  refused(kHeader + kRow0 + "0.01,0,0,0.5,0,0,-0.75,1500,20,0,0,0,0,0,0,0\n", "bad.csv:6: grip_max_force_N");
  refused(kHeader + kRow0 + "0.01,0,3,0.5,0,0,-0.75,1500,20,12,0,0,0,0,0,0\n", "bad.csv:6: anchor: more than");
  CHECK_THROWS_WITH(uhaptics::readHandRecording("/nonexistent/hand.csv"),
                    Catch::Contains("/nonexistent/hand.csv: cannot read"));
  // A recording made in code is checked by the hand too.
  ScriptedHandOptions options;
  auto short_recording = std::make_shared<HandRecording>(parseText(kHeader + kRow0 + kRow1));
  short_recording->samples[1].time = 0.0;
  options.recording = short_recording;
  CHECK_THROWS_AS(ScriptedHand(options, 0.025, Vec3::Zero()), uhaptics::Error);
}
