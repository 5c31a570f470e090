// Session statistics: contact episodes with hysteresis, peaks, faults, the JSON file.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "uhaptics/chai3d/session_stats.hpp"
#include "uhaptics/core/fault.hpp"
#include "uhaptics/tools/alloc_probe.hpp"

using uhaptics::SessionStats;

TEST_CASE("session stats count contact episodes, not ticks above the threshold", "[chai3d][stats]") {
  SessionStats stats(1.0);
  stats.start(10.0);
  // Ripple around the threshold (0.7..1.2 N) is one contact: it must fall below 0.5 N to end.
  for (const double f : {0.0, 1.2, 0.7, 1.1, 0.8, 0.4, 0.0, 2.5, 0.1}) stats.recordTick(f, 10.0 * f, false);
  stats.recordTick(0.0, 0.0, true);
  stats.recordFault();
  const auto s = stats.snapshot(12.0);
  CHECK(s.ticks == 10);
  CHECK(s.contacts == 2);
  CHECK(s.contact_ticks == 5);  // 1.2 0.7 1.1 0.8 | 2.5
  CHECK(s.peak_force == 2.5);
  CHECK(s.peak_output == 25.0);
  CHECK(s.faults == 2);
  CHECK(s.seconds == 2.0);
  CHECK(s.rate_hz == 5.0);
}

TEST_CASE("recording a tick allocates nothing", "[chai3d][stats]") {
  SessionStats stats;
  stats.start(0.0);
  uhaptics::tools::AllocationScope scope;
  for (int i = 0; i < 1000; ++i) stats.recordTick(0.001 * i, 1.0, false);
  CHECK(scope.count() == 0);
}

TEST_CASE("stats file is complete JSON written atomically", "[chai3d][stats]") {
  SessionStats stats;
  stats.start(0.0);
  stats.recordTick(3.0, 1.5, false);
  const std::string path = "uhaptics-chai3d-stats-test.json";
  uhaptics::writeFileAtomically(path, uhaptics::formatStatsJson(stats.snapshot(1.0), "exo", "sim", "subspace \"proxy\""));
  std::ifstream file(path);
  std::stringstream text;
  text << file.rdbuf();
  CHECK_THAT(text.str(), Catch::Contains("\"device\": \"exo\""));
  CHECK_THAT(text.str(), Catch::Contains("\"renderer\": \"subspace \\\"proxy\\\"\""));
  CHECK_THAT(text.str(), Catch::Contains("\"ticks\": 1,"));
  CHECK_THAT(text.str(), Catch::Contains("\"contacts\": 1,"));
  CHECK_THAT(text.str(), Catch::Contains("\"peak_force_N\": 3,"));
  CHECK(!std::ifstream(path + ".tmp").good());  // the temporary was renamed away
  std::remove(path.c_str());
  CHECK_THROWS_AS(uhaptics::writeFileAtomically("/nonexistent-dir/x.json", "{}"), uhaptics::Error);
}

TEST_CASE("renderer figures count and keep maxima, reset on start, and reach the JSON", "[chai3d][stats]") {
  using Kind = uhaptics::RendererFigure::Kind;
  SessionStats stats;
  const int engagements = stats.declareFigure("engagements", Kind::kCount);
  const int depth = stats.declareFigure("max_penetration_mm", Kind::kMaximum);
  CHECK_THROWS_AS(stats.declareFigure("engagements", Kind::kCount), uhaptics::Error);
  stats.start(0.0);
  {
    uhaptics::tools::AllocationScope scope;
    stats.count(engagements);
    stats.count(engagements, 2);
    stats.observeMaximum(depth, 0.4);
    stats.observeMaximum(depth, 0.25);
    stats.observeMaximum(depth, std::nan(""));
    stats.count(99);  // unknown ids are ignored, never written out of bounds
    CHECK(scope.count() == 0);
  }
  auto s = stats.snapshot(1.0);
  REQUIRE(s.figure_count == 2);
  CHECK(s.figure("engagements")->value == 3.0);
  CHECK(s.figure("max_penetration_mm")->value == 0.4);
  CHECK(s.figure("nothing") == nullptr);
  const std::string json = uhaptics::formatStatsJson(s, "tau", "sim", "lqr wall");
  CHECK_THAT(json, Catch::Contains("\"renderer_figures\": {\n    \"engagements\": 3,\n    \"max_penetration_mm\": 0.4\n  }"));
  stats.start(2.0);
  s = stats.snapshot(3.0);
  CHECK(s.figure_count == 2);
  CHECK(s.figure("engagements")->value == 0.0);

  SessionStats full;
  static const char* const names[] = {"a", "b", "c", "d", "e", "f", "g", "h", "i", "j", "k", "l", "m",
                                      "n", "o", "p", "q", "r", "s", "t", "u", "v", "w", "x", "y", "z"};
  static_assert(uhaptics::SessionStatsSnapshot::kMaxFigures < 26, "enough names for a full recorder");
  for (int i = 0; i < uhaptics::SessionStatsSnapshot::kMaxFigures; ++i) full.declareFigure(names[i], Kind::kCount);
  CHECK_THROWS_AS(full.declareFigure(names[uhaptics::SessionStatsSnapshot::kMaxFigures], Kind::kCount),
                  uhaptics::Error);
}

TEST_CASE("a value figure keeps its latest finite reading, also when it falls", "[chai3d][stats]") {
  using Kind = uhaptics::RendererFigure::Kind;
  SessionStats stats;
  const int energy = stats.declareFigure("energy_out_mJ", Kind::kValue);
  stats.start(0.0);
  {
    uhaptics::tools::AllocationScope scope;
    stats.setValue(energy, 2.5);
    stats.setValue(energy, -0.75);
    stats.setValue(energy, std::nan(""));
    stats.setValue(99, 1.0);  // unknown ids are ignored
    CHECK(scope.count() == 0);
  }
  const auto s = stats.snapshot(1.0);
  CHECK(s.figure("energy_out_mJ")->value == -0.75);
  CHECK_THAT(uhaptics::formatStatsJson(s, "tau", "sim", "spring"), Catch::Contains("\"energy_out_mJ\": -0.75"));
}

TEST_CASE("session stats keep the box of visited positions", "[chai3d][stats]") {
  SessionStats stats;
  stats.start(0.0);
  CHECK(stats.snapshot(1.0).visited_min[0] > stats.snapshot(1.0).visited_max[0]);  // empty before a tick
  stats.recordPosition(0.1, -0.2, 0.3);
  stats.recordPosition(-0.5, 0.4, std::nan(""));  // ignored whole: a non-finite reading is no position
  stats.recordPosition(0.2, -0.3, 0.0);
  const auto s = stats.snapshot(1.0);
  CHECK(s.visited_min == std::array<double, 3>{0.1, -0.3, 0.0});
  CHECK(s.visited_max == std::array<double, 3>{0.2, -0.2, 0.3});
  CHECK_THAT(uhaptics::formatStatsJson(s, "exo", "sim", "x"), Catch::Contains("\"visited_min_radii\": [0.1, -0.3, 0]"));
  CHECK_THAT(uhaptics::formatStatsJson(s, "exo", "sim", "x"), Catch::Contains("\"visited_max_radii\": [0.2, -0.2, 0.3]"));
}

TEST_CASE("the referee's figures reach the JSON as an object, null where nothing was measured",
          "[chai3d][stats][referee]") {
  SessionStats stats;
  stats.start(0.0);
  uhaptics::SessionStatsSnapshot s = stats.snapshot(1.0);
  CHECK_THAT(uhaptics::formatStatsJson(s, "tau", "usb", "x"), !Catch::Contains("referee"));  // none on usb
  s.has_referee = true;
  s.referee.contacts = 2;
  s.referee.max_true_penetration_mm = 0.75;
  s.referee.generated_energy_mJ = -1.5;
  const std::string json = uhaptics::formatStatsJson(s, "tau", "sim", "x");
  CHECK_THAT(json, Catch::Contains("\"referee\": {"));
  CHECK_THAT(json, Catch::Contains("\"contacts\": 2,"));
  CHECK_THAT(json, Catch::Contains("\"max_true_penetration_mm\": 0.75,"));
  CHECK_THAT(json, Catch::Contains("\"generated_energy_mJ\": -1.5,"));
  CHECK_THAT(json, Catch::Contains("\"rendered_stiffness_N_per_m\": null,"));  // no hold: NaN -> null
  CHECK_THAT(json, Catch::EndsWith("}\n}\n"));
}

TEST_CASE("the board's servo timing reaches the JSON as an object, absent without a board",
          "[chai3d][stats]") {
  SessionStats stats;
  stats.start(0.0);
  uhaptics::SessionStatsSnapshot s = stats.snapshot(1.0);
  CHECK_THAT(uhaptics::formatStatsJson(s, "tau", "sim", "x"), !Catch::Contains("servo_timing"));
  s.has_servo_timing = true;
  s.servo_timing.samples = 6489;
  s.servo_timing.nominal_period_us = 1000.0;
  s.servo_timing.period.max_us = 11371.5;
  s.servo_timing.wake_latency.max_us = 10425.25;
  s.servo_timing.overruns = 15;
  s.servo_timing.missed_periods = 27;
  const std::string json = uhaptics::formatStatsJson(s, "tau", "emulated", "x");
  CHECK_THAT(json, Catch::Contains("\"servo_timing\": {"));
  CHECK_THAT(json, Catch::Contains("\"samples\": 6489,"));
  CHECK_THAT(json, Catch::Contains("\"period_max_us\": 11371.5,"));
  CHECK_THAT(json, Catch::Contains("\"wake_latency_max_us\": 10425.25,"));
  CHECK_THAT(json, Catch::Contains("\"overruns\": 15,"));
  CHECK_THAT(json, Catch::Contains("\"missed_periods\": 27\n  }"));
  CHECK_THAT(json, Catch::EndsWith("}\n}\n"));
}
