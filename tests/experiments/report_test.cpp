#include "uhaptics/experiments/report.hpp"

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>

namespace fs = std::filesystem;
using namespace uhaptics::experiments;

TEST_CASE("the report gathers experiments by paper with their tables and figures") {
  const fs::path root = fs::temp_directory_path() / "uhaptics_report_test";
  fs::remove_all(root);
  fs::create_directories(root / "b-exp");
  fs::create_directories(root / "a-exp");
  fs::create_directories(root / "no-table");
  ReproductionTable t1, t2;
  t1.addWithin("003", "K at home", 123, 123.2, 0.5, "-");
  t2.addBound("000", "passive frames", 100, "= 100 %", true, "%");
  t2.addBound("000", "something broken", 3, "< 1", false, "-");
  t1.writeCsv((root / "a-exp" / "reproduction.csv").string());
  t2.writeCsv((root / "b-exp" / "reproduction.csv").string());
  std::ofstream(root / "b-exp" / "fig.png") << "png";
  std::ofstream(root / "b-exp" / "summary.txt") << "hello summary\n";

  const auto ex = collectExperiments(root.string());
  REQUIRE(ex.size() == 2);
  CHECK(ex[0].folder == "b-exp");  // paper 000 sorts before 003
  REQUIRE(ex[0].figures.size() == 1);
  CHECK(ex[0].figures[0] == "b-exp/fig.png");
  const std::string md = renderMarkdown(ex, {{"seed", "1"}});
  CHECK(md.find("**2 of 3 checks pass**") != std::string::npos);
  CHECK(md.find("**FAIL**") != std::string::npos);
  CHECK(md.find("![b-exp/fig.png](b-exp/fig.png)") != std::string::npos);
  CHECK(md.find("hello summary") != std::string::npos);
  CHECK(md.find("| seed | 1 |") != std::string::npos);
  CHECK(md.find("Paper 000") < md.find("Paper 003"));
  fs::remove_all(root);
}
