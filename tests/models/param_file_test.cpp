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

TEST_CASE("a key no loader reads is refused, naming it and the nearest known key") {
  const auto p = ParamFile::parse(R"({"device": "demo", "format_version": 1, "description": "allowed",
    "geometry": {"length": {"value": 0.045, "unit": "m", "why": "allowed"}, "cuont": 3, "about": "allowed"},
    "usb": {"anything": 1}})", "demo.json");
  p.requireFormat("demo", 1);
  CHECK(p.number("geometry/length", 0.0, 1.0) == 0.045);
  CHECK(p.numberOr("geometry/count", 2.0, 1.0, 10.0) == 2.0);  // misspelt in the file: default taken...
  // ...and the misspelling refused once the loader is done.
  CHECK_THROWS_WITH(p.rejectUnreadKeys({"usb"}), Contains("demo.json: unknown key 'geometry/cuont'") &&
                                                     Contains("did you mean 'geometry/count'"));
  CHECK_THROWS_WITH(p.rejectUnreadKeys(), Contains("'usb/anything'"));
  // A required key misspelt is reported where it is missed, with the file's nearest key.
  const auto q = ParamFile::parse(R"({"geometry": {"lenght": 0.045}})", "typo.json");
  CHECK_THROWS_WITH(q.number("geometry/length", 0.0, 1.0),
                    Contains("typo.json: missing required field 'geometry/length'") &&
                        Contains("the file has 'geometry/lenght'"));
  // A member of a documented entry other than value and the descriptive ones is a key too.
  const auto r = ParamFile::parse(R"({"x": {"value": 1.0, "unti": "m"}})", "entry.json");
  CHECK(r.number("x", 0.0, 2.0) == 1.0);
  CHECK_THROWS_WITH(r.rejectUnreadKeys(), Contains("'x/unti'"));
  // An empty section whose fields the loader asked for is known (e.g. a selection's "hand": {}); an
  // empty section nobody asked about is not.
  const auto e = ParamFile::parse(R"({"hand": {}, "hnad": {}})", "empty.json");
  CHECK(e.numberOr("hand/lap_time", 4.0, 0.1, 10.0) == 4.0);
  CHECK_THROWS_WITH(e.rejectUnreadKeys(), Contains("'hnad'") && !Contains("'hand'"));
}

TEST_CASE("the loader's reads are the file's schema") {
  const auto p = ParamFile::parse(kGood, "demo.json");
  p.number("geometry/length", 0.0, 1.0);
  p.numberOr("geometry/absent", 1.0, 0.0, 2.0);
  p.vector<2>("limits", 0.0, 5.0);
  const auto fields = p.fields();
  REQUIRE(fields.size() == 3);
  CHECK(fields[0].key == "geometry/length");
  CHECK(fields[0].unit == "m");
  CHECK(fields[0].hi == 1.0);
  CHECK_FALSE(fields[1].required);
  CHECK(fields[2].kind == ParamField::Kind::kNumbers);
  CHECK(fields[2].count == 2);
}

TEST_CASE("a number beyond a double and a folder are named as such, with the file") {
  CHECK_THROWS_WITH(ParamFile::parse(R"({"a": {"b": {"value": [0.0, 1e999]}}})", "big.json"),
                    Contains("big.json: field 'a/b' is not a finite number"));
  CHECK_THROWS_WITH(ParamFile::parse(R"({"a": -1e999})", "big.json"), Contains("big.json: field 'a'"));
  CHECK_THROWS_WITH(ParamFile::load("/tmp"), Contains("/tmp: is a folder"));
  CHECK_THROWS_WITH(ParamFile::parse(R"({"a": 1})", "int.json").integer("a", 2, 5), Contains("outside [2, 5]"));
  CHECK_THROWS_WITH(ParamFile::parse(R"({"a": 18446744073709551615})", "int.json").integer("a", 0, 5),
                    Contains("outside [0, 5]"));
}

TEST_CASE("edit distance counts a swap of neighbouring letters once") {
  CHECK(editDistance("length", "length") == 0);
  CHECK(editDistance("length", "lenght") == 1);
  CHECK(editDistance("gravity", "gravty") == 1);
  CHECK(editDistance("", "abc") == 3);
}
