// The docs' generated tables (docs/reproduction.md, docs/benchmarks.md): uhaptics-report rewrites
// what lies between a region's markers and nothing else, a second rewrite changes nothing, and a
// file it cannot rewrite is refused with a message saying why. The papers' headings come from the
// device definitions.
#include <catch2/catch.hpp>
#include <string>

#include "uhaptics/backends/device_definition.hpp"
#include "uhaptics/experiments/report.hpp"

using namespace uhaptics::experiments;

namespace {

std::vector<ExperimentResult> twoExperiments() {
  ExperimentResult a, b;
  a.folder = "tau-study";
  a.table.addWithin("001", "fastest pole", 2480, 2400, 248, "rad/s");
  a.table.addBound("001", "max penetration | LQR", 0.09, "< 1 mm", true, "mm");
  b.folder = "rhi-experiments";
  b.table.addWithin("003", "K at home", 123, 123.2, 0.5, "");
  b.table.addWithin("003", "Table I force", 8.564, 11.18, 1.28, "N");
  b.table.markNeedsData("the base frame is not published");
  b.table.addBound("003", "broken", 3, "< 1", false, "");
  return {b, a};  // paper 003's experiment first: the table still groups by paper
}

const std::string kBefore = "# Title\n\nHand-written prose, kept.\r\n\n<!-- begin generated: reproduction -->\n"
                            "| stale | table |\n|---|---|\n<!-- end generated: reproduction -->\n\nMore prose.\n"
                            "<!-- begin generated: reproduction-summary -->\n<!-- end generated: reproduction-summary -->\n"
                            "Closing line without a newline";

// Google Benchmark's JSON, cut to what the report reads: two servo ticks (one in ms), an aggregate
// (skipped), and a swept knob with a default.
const std::string kBenchJson = R"({
  "context": {"date": "2025-01-01T00:00:00", "num_cpus": 2, "mhz_per_cpu": 2100},
  "benchmarks": [
    {"name": "BM_ExoTickStandard/contact:1", "run_type": "iteration", "cpu_time": 541.0, "time_unit": "ns",
     "allocs_per_tick": 0},
    {"name": "BM_SimulatedTauServoPeriod", "run_type": "iteration", "cpu_time": 0.0192, "time_unit": "ms",
     "allocs_per_step": 0},
    {"name": "BM_ExoTickStandard/contact:1_mean", "run_type": "aggregate", "cpu_time": 1.0, "time_unit": "ns",
     "allocs_per_tick": 0},
    {"name": "BM_DareTolerance/neg_log10_tol:1", "run_type": "iteration", "cpu_time": 118.0, "time_unit": "us",
     "error": 8e-6, "default": 0},
    {"name": "BM_DareTolerance/neg_log10_tol:13", "run_type": "iteration", "cpu_time": 150.0, "time_unit": "us",
     "error": 1.7e-15, "default": 1}
  ]
})";

}  // namespace

TEST_CASE("a generated region is rewritten from the reproduction tables and nothing outside it changes",
          "[experiments][report]") {
  const auto regions = reproductionRegions(twoExperiments(), {{"commit", "abc123"}});
  const std::string once = rewriteGeneratedRegions(kBefore, regions, "doc.md");
  // Round trip: rewriting the rewritten file gives the same file.
  CHECK(rewriteGeneratedRegions(once, regions, "doc.md") == once);
  // Everything outside the markers is byte for byte what it was (the CRLF line and the last line
  // without a newline included), and the markers stay.
  const std::string begin = "<!-- begin generated: reproduction -->\n";
  const std::string end = "<!-- end generated: reproduction -->\n";
  REQUIRE(once.find(begin) != std::string::npos);
  CHECK(once.substr(0, once.find(begin)) == kBefore.substr(0, kBefore.find(begin)));
  const std::string after = "\nMore prose.\n";
  CHECK(once.substr(once.find(end), end.size() + after.size()) == end + after);
  const std::string between = once.substr(once.find(begin) + begin.size(), once.find(end) - once.find(begin) - begin.size());
  CHECK(between.find("stale") == std::string::npos);
  CHECK(between.find("| 001 | fastest pole | 2480 | 2400 | rad/s |") != std::string::npos);
  CHECK(between.find("max penetration \\| LQR") != std::string::npos);  // a '|' in a cell is escaped
  CHECK(between.find("| needs data |") != std::string::npos);
  CHECK(between.find("| **FAIL** |") != std::string::npos);
  CHECK(between.find("- needs data: Table I force: the base frame is not published") != std::string::npos);
  CHECK(between.find("**3 of 5 checks pass**, 1 fail, 1 need data") != std::string::npos);
  CHECK(between.find("commit abc123") != std::string::npos);
  // Rows grouped by paper: 001 before 003 although the 003 experiment came first.
  CHECK(between.find("| 001 |") < between.find("| 003 |"));
  REQUIRE(once.size() >= 30);
  CHECK(once.substr(once.size() - 30) == kBefore.substr(kBefore.size() - 30));
  // The summary region: one row per paper with its title from the device definition.
  const std::string& summary = regions.at("reproduction-summary");
  CHECK(summary.find("| 003 *" + uhaptics::findDeviceByPaper("003")->paper.title + "* |") != std::string::npos);
  CHECK(summary.find("| 3 | 1 | 1 | 1 |") != std::string::npos);
  CHECK(once.find(summary) != std::string::npos);
}

TEST_CASE("content outside the markers is kept exactly", "[experiments][report]") {
  // Stronger than the above: removing the regions' content from both files leaves the same text.
  const auto regions = reproductionRegions(twoExperiments(), {});
  const std::string once = rewriteGeneratedRegions(kBefore, regions, "doc.md");
  auto outside = [](std::string text) {
    for (const std::string name : {"reproduction", "reproduction-summary"}) {
      const std::string begin = "<!-- begin generated: " + name + " -->\n";
      const std::size_t from = text.find(begin) + begin.size();
      text.erase(from, text.find("<!-- end generated: " + name + " -->") - from);
    }
    return text;
  };
  CHECK(outside(once) == outside(kBefore));
  CHECK(generatedRegionNames(once) == std::vector<std::string>{"reproduction", "reproduction-summary"});
}

TEST_CASE("a file the report cannot rewrite is refused with the reason", "[experiments][report]") {
  const auto regions = reproductionRegions(twoExperiments(), {});
  CHECK_THROWS_WITH(rewriteGeneratedRegions("# No markers\n\n| a | b |\n", regions, "plain.md"),
                    Catch::StartsWith("plain.md has no generated region") &&
                        Catch::Contains("<!-- begin generated: NAME -->") && Catch::Contains("reproduction"));
  CHECK_THROWS_WITH(rewriteGeneratedRegions("<!-- begin generated: reproduction -->\n| a |\n", regions, "open.md"),
                    Catch::Contains("open.md:1") && Catch::Contains("no end marker"));
  CHECK_THROWS_WITH(rewriteGeneratedRegions("<!-- begin generated: bench-ticks -->\n<!-- end generated: bench-ticks -->\n",
                                            regions, "bench.md"),
                    Catch::Contains("region 'bench-ticks' cannot be generated from this run") &&
                        Catch::Contains("--bench-json"));
  CHECK_THROWS_WITH(rewriteGeneratedRegions("<!-- begin generated: reproduction -->\n<!-- begin generated: "
                                            "reproduction-summary -->\n<!-- end generated: reproduction -->\n",
                                            regions, "nested.md"),
                    Catch::Contains("nested.md:2") && Catch::Contains("begins inside region 'reproduction'"));
  CHECK_THROWS_WITH(rewriteGeneratedRegions("<!-- end generated: reproduction -->\n", regions, "end.md"),
                    Catch::Contains("without its begin marker"));
  const std::string twice = "<!-- begin generated: reproduction -->\n<!-- end generated: reproduction -->\n";
  CHECK_THROWS_WITH(rewriteGeneratedRegions(twice + twice, regions, "twice.md"), Catch::Contains("appears twice"));
  // No experiment rows: no region, so a doc's region is refused rather than emptied.
  CHECK(reproductionRegions({}, {}).empty());
}

TEST_CASE("the benchmark tables come from Google Benchmark's JSON and round-trip", "[experiments][report]") {
  const auto regions = benchmarkRegions(kBenchJson, {{"command", "tools/run-bench"}});
  REQUIRE(regions.count("bench-ticks") == 1);
  REQUIRE(regions.count("bench-time-vs-error") == 1);
  const std::string& ticks = regions.at("bench-ticks");
  CHECK(ticks.find("| `BM_ExoTickStandard/contact:1` | 0.541 us | 0 | 1848 |") != std::string::npos);
  CHECK(ticks.find("| `BM_SimulatedTauServoPeriod` | 19.2 us | 0 | 52 |") != std::string::npos);
  CHECK(ticks.find("_mean") == std::string::npos);  // aggregates are not runs
  CHECK(ticks.find("2 CPUs at 2100 MHz") != std::string::npos);
  CHECK(ticks.find("command tools/run-bench") != std::string::npos);
  const std::string& tve = regions.at("bench-time-vs-error");
  CHECK(tve.find("| `BM_DareTolerance` |  | neg_log10_tol | 1: 118 us 8e-06; **13: 150 us 1.7e-15** |") !=
        std::string::npos);
  const std::string doc = "Prose.\n<!-- begin generated: bench-ticks -->\n<!-- end generated: bench-ticks -->\n"
                          "Between.\n<!-- begin generated: bench-time-vs-error -->\nold\n"
                          "<!-- end generated: bench-time-vs-error -->\nAfter.\n";
  const std::string once = rewriteGeneratedRegions(doc, regions, "benchmarks.md");
  CHECK(rewriteGeneratedRegions(once, regions, "benchmarks.md") == once);
  CHECK(once.find(ticks) != std::string::npos);
  CHECK(once.find("\nold\n") == std::string::npos);
  CHECK(once.rfind("Prose.\n", 0) == 0);
  CHECK(once.find("\nBetween.\n") != std::string::npos);
  CHECK(once.substr(once.size() - 7) == "After.\n");
  CHECK(regions.count("bench-chai3d-tick") == 0);  // no CHAI3D tick runs in this JSON
  CHECK_THROWS_WITH(benchmarkRegions("{\"context\": {}}", {}), Catch::Contains("no \"benchmarks\" array"));
  CHECK_THROWS_WITH(benchmarkRegions("not json", {}), Catch::Contains("does not parse"));
}

TEST_CASE("the report heads each paper's rows with the title its device definition gives", "[experiments][report]") {
  for (const uhaptics::DeviceDefinition* d : uhaptics::deviceDefinitions()) {
    INFO(d->name);
    const std::string heading = paperHeading(d->paper.id);
    CHECK(heading.rfind("Paper " + d->paper.id + " — " + d->paper.title, 0) == 0);
  }
  CHECK(paperHeading("chai3d").find("CHAI3D") != std::string::npos);
  CHECK(paperHeading("999") == "Paper 999");
}

TEST_CASE("the CHAI3D tick table: what each device adds to CHAI3D's own tick", "[experiments][report]") {
  const std::string json = R"({"context": {"date": "d", "num_cpus": 2, "mhz_per_cpu": 2000}, "benchmarks": [
    {"name": "BM_Chai3dTick/tau/contact/chai3d", "run_type": "iteration", "cpu_time": 10000, "time_unit": "ns", "allocs_per_tick": 0.5},
    {"name": "BM_Chai3dTick/tau/contact/uhaptics", "run_type": "iteration", "cpu_time": 14, "time_unit": "us", "allocs_per_tick": 0.5},
    {"name": "BM_Chai3dTick/tau/free/chai3d", "run_type": "iteration", "cpu_time": 500, "time_unit": "ns", "allocs_per_tick": 0},
    {"name": "BM_Chai3dTick/tau/free/uhaptics", "run_type": "iteration", "cpu_time": 1300, "time_unit": "ns", "allocs_per_tick": 0},
    {"name": "BM_Chai3dTick/exo/contact/chai3d", "run_type": "iteration", "cpu_time": 10000, "time_unit": "ns"},
    {"name": "BM_Chai3dTick/exo/contact/uhaptics", "run_type": "iteration", "error_occurred": true},
    {"name": "BM_Chai3dTick/tau/contact/uhaptics_mean", "run_type": "aggregate", "cpu_time": 1}]})";
  const auto regions = benchmarkRegions(json, {});
  REQUIRE(regions.count("bench-chai3d-tick") == 1);
  CHECK(regions.count("bench-ticks") == 0);  // the CHAI3D ticks have their own table
  const std::string& t = regions.at("bench-chai3d-tick");
  // tau: 4 us over CHAI3D's 10 us contact tick (40 %); 0.8 us in free space, 20 % of its 4 us.
  CHECK(t.find("| tau | 10 us / 0.5 us | 14 us / 1.3 us | 4 us (40 %) | 0.8 us (20 %) | 0.5 / 0 |") != std::string::npos);
  CHECK(t.find("| exo |") == std::string::npos);  // incomplete (a run failed): no row
}
