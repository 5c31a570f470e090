#include "uhaptics/experiments/reproduction.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>

using uhaptics::experiments::ReproductionTable;

TEST_CASE("reproduction tables decide pass/fail and round-trip through CSV") {
  ReproductionTable t;
  t.addWithin("003", "K at home", 123.0, 123.4, 0.5, "-");
  t.addWithin("003", "zeta, at home", 3.3, 3.9, 0.05, "-");
  t.addBound("001", "max penetration", 0.8, "< 1 mm", true, "mm");
  t.addBound("001", "broken", std::nan(""), "< 1", true, "mm");
  REQUIRE(t.rows().size() == 4);
  CHECK(t.rows()[0].pass);
  CHECK_FALSE(t.rows()[1].pass);
  CHECK(t.rows()[2].pass);
  CHECK_FALSE(t.rows()[3].pass);  // a NaN measurement never passes
  CHECK_FALSE(t.allPass());
  const std::string path = "reproduction_table_test.csv";
  t.writeCsv(path);
  const auto back = ReproductionTable::readCsv(path);
  std::remove(path.c_str());
  REQUIRE(back.rows().size() == 4);
  CHECK(back.rows()[1].quantity == "zeta, at home");
  CHECK(back.rows()[0].measured == Approx(123.4));
  CHECK(back.rows()[1].pass == false);
  CHECK(t.format().find("FAIL") != std::string::npos);
}

TEST_CASE("rows that need unpublished data are shown with their reason and do not fail the run") {
  ReproductionTable t;
  t.addWithin("003", "K at home", 123.0, 123.4, 0.5, "-");
  t.addWithin("003", "Table I force", 8.564, 11.2, 1.3, "N");
  t.markNeedsData("the base frame is not published");
  CHECK_FALSE(t.rows()[1].pass);
  CHECK_FALSE(t.rows()[1].fails());
  CHECK(t.allPass());
  CHECK(uhaptics::experiments::resultWord(t.rows()[1]) == "needs data");
  CHECK(t.format().find("needs data: Table I force: the base frame is not published") != std::string::npos);
  const std::string path = "reproduction_needs_data_test.csv";
  t.writeCsv(path);
  const auto back = ReproductionTable::readCsv(path);
  std::remove(path.c_str());
  REQUIRE(back.rows().size() == 2);
  CHECK(back.rows()[1].needs_data == "the base frame is not published");
  CHECK(back.allPass());
  // A missed row without a reason still fails; a reason cannot be attached to nothing.
  t.addWithin("003", "zeta", 3.3, 3.9, 0.05, "-");
  CHECK_FALSE(t.allPass());
  CHECK_THROWS(ReproductionTable().markNeedsData("why"));
}

TEST_CASE("reproduction tables read files with CRLF line ends (Python's csv module writes them)") {
  const std::string path = "reproduction_crlf_test.csv";
  {
    std::ofstream out(path, std::ios::binary);
    out << "paper,quantity,published,measured,criterion,pass,unit,needs_data\r\n"
        << "chai3d,run,nan,5,rule,FAIL,ticks,\r\n";
  }
  const auto t = ReproductionTable::readCsv(path);
  std::remove(path.c_str());
  REQUIRE(t.rows().size() == 1);
  CHECK(t.rows()[0].needs_data.empty());
  CHECK(t.rows()[0].fails());
}

namespace {
void writeFile(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

// The message readCsv throws for `text`, or "" when it reads the file.
std::string refusal(const std::string& text) {
  const std::string path = "reproduction_refusal_test.csv";
  writeFile(path, text);
  try {
    ReproductionTable::readCsv(path);
  } catch (const std::runtime_error& e) {
    std::remove(path.c_str());
    return e.what();
  }
  std::remove(path.c_str());
  return "";
}
}  // namespace

TEST_CASE("an accepted interval decides a row and survives the CSV exactly") {
  using uhaptics::experiments::Accepted;
  CHECK(Accepted::below(1.0).contains(0.999));
  CHECK_FALSE(Accepted::below(1.0).contains(1.0));
  CHECK(Accepted::atMost(1.0).contains(1.0));
  CHECK(Accepted::within(2.0, 0.5).contains(2.5));
  CHECK_FALSE(Accepted::within(2.0, 0.5).contains(std::nan("")));
  CHECK_FALSE(Accepted::nothing().contains(0.0));
  const Accepted odd = Accepted::openInterval(0.1 * 3.0, 1.0 / 3.0);
  const Accepted back = Accepted::parse(odd.text());
  CHECK(back.min == odd.min);  // exact: the report decides the row as the tool did
  CHECK(back.max == odd.max);
  CHECK(back.min_open);
  CHECK_THROWS(Accepted::parse("[2, 1]"));
  CHECK_THROWS(Accepted::parse("[a, 1]"));
  CHECK_THROWS(Accepted::parse("1, 2"));

  ReproductionTable t;
  t.addBound("001", "penetration", 0.8, "< 1 mm", Accepted::below(1.0), "mm");
  t.addBound("001", "overshoot", 2.5, "< 2 %", Accepted::below(2.0), "%");
  CHECK(t.rows()[0].pass);
  CHECK_FALSE(t.rows()[1].pass);
  const std::string path = "reproduction_accepts_test.csv";
  t.writeCsv(path);
  const auto read = ReproductionTable::readCsv(path);
  std::remove(path.c_str());
  CHECK(read.recheckableRows() == 2);
  CHECK(read.rows()[0].pass);
  CHECK_FALSE(read.rows()[1].pass);
}

TEST_CASE("a malformed reproduction table is refused with the file and the row named") {
  const std::string header = "paper,quantity,published,measured,criterion,pass,unit,needs_data,accepts\n";
  const std::string row = "001,pen,nan,0.8,< 1 mm,pass,mm,,\"(-inf, 1)\"\n";
  CHECK(refusal(header + row).empty());
  CHECK(refusal("").find("empty file") != std::string::npos);
  CHECK(refusal("garbage\n1,2\n").find("line 1 is not the header") != std::string::npos);
  CHECK(refusal(header).find("no rows") != std::string::npos);
  CHECK(refusal(header + row + "001,pen,nan,abc,< 1 mm,pass,mm,,\n").find("row 2 (line 3): measured 'abc'") !=
        std::string::npos);
  CHECK(refusal(header + "001,pen,nan\n").find("row 1 (line 2): 3 cells") != std::string::npos);
  CHECK(refusal(header + "001,pen,nan,0.8,< 1 mm,maybe,mm,,\n").find("result 'maybe'") != std::string::npos);
  // The result column must agree with the row's own interval: a pass that is not one is refused.
  CHECK(refusal(header + "001,pen,nan,1.5,< 1 mm,pass,mm,,\"(-inf, 1)\"\n").find("row 1 (line 2) 'pen'") !=
        std::string::npos);
  CHECK(refusal(header + "001,pen,nan,1.5,< 1 mm,FAIL,mm,,\"[2, 1]\"\n").find("row 1") != std::string::npos);
  std::filesystem::create_directories("reproduction_folder_test.csv");
  CHECK_THROWS_WITH(ReproductionTable::readCsv("reproduction_folder_test.csv"),
                    Catch::Contains("a folder, not a reproduction table"));
  std::filesystem::remove("reproduction_folder_test.csv");
}
