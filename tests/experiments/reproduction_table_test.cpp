#include "uhaptics/experiments/reproduction.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <fstream>

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
