#include "uhaptics/models/param_file.hpp"

#include <catch2/catch.hpp>

using namespace uhaptics;
using Catch::Matchers::Contains;

namespace {
const char* kGood = R"({
  "device": "demo", "format_version": 1,
  "geometry": {"length": {"value": 0.045, "unit": "m", "source": "assumed"}, "count": 3},
  "limits": [1.0, 2.0]
})";
}

TEST_CASE("parameter files read documented and bare values") {
  const auto p = ParamFile::parse(kGood, "demo.json");
  p.requireFormat("demo", 1);
  CHECK(p.number("geometry/length", 0.0, 1.0) == 0.045);
  CHECK(p.integer("geometry/count", 1, 10) == 3);
  CHECK(p.vector<2>("limits", 0.0, 5.0) == Vec2(1.0, 2.0));
  CHECK(p.numberOr("geometry/missing", 7.0, 0.0, 10.0) == 7.0);
}

TEST_CASE("parameter file errors name the file, the field and the range") {
  const auto p = ParamFile::parse(kGood, "demo.json");
  CHECK_THROWS_WITH(p.number("geometry/length", 0.1, 1.0),
                    Contains("demo.json") && Contains("geometry/length") && Contains("0.045 m") &&
                        Contains("[0.1, 1]"));
  CHECK_THROWS_WITH(p.number("geometry/absent", 0, 1), Contains("missing required field 'geometry/absent'"));
  CHECK_THROWS_WITH(p.vector<3>("limits", 0, 5), Contains("array of 3"));
  CHECK_THROWS_WITH(p.integer("geometry/length", 0, 5), Contains("must be an integer"));
  CHECK_THROWS_WITH(p.requireFormat("other", 1), Contains("expected 'other'"));
  CHECK_THROWS_WITH(p.requireFormat("demo", 2), Contains("format_version 1 is not supported"));
  CHECK_THROWS_WITH(ParamFile::parse("{ not json", "bad.json"), Contains("bad.json: not valid JSON"));
  CHECK_THROWS_WITH(ParamFile::load("/nonexistent/x.json"), Contains("cannot open"));
}
