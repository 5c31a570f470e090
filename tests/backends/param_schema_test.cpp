// Every device's parameter file against its schema: the schema is what the device's loaders read
// (ParamFile::fields()), docs/parameter-files.md shows it, and a generated set of bad inputs for
// every field of every shipped file is refused with uhaptics::Error naming the file and the field.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <sstream>

#include "uhaptics/backends/board_catalog.hpp"
#include "uhaptics/backends/device_definition.hpp"
#include "uhaptics/core/fault.hpp"
#include "uhaptics/models/param_file.hpp"

using namespace uhaptics;
using nlohmann::json;

namespace {

std::string readText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

struct Shipped {
  const DeviceDefinition* device;
  std::string path;
  std::string text;
  std::vector<ParamField> schema;
};

// The shipped file, loaded as the board layer loads it (the model's fields and the "usb" section).
Shipped shipped(const DeviceDefinition& d) {
  Shipped s{&d, std::string(UHAPTICS_PARAMS_DIR) + "/" + d.params_file, {}, {}};
  s.text = readText(s.path);
  const ParamFile file = ParamFile::parse(s.text, s.path);
  boardSpecFromParams(d, file);
  s.schema = file.fields();
  // The model's fields first, then the board's section, each in reading order.
  std::stable_partition(s.schema.begin(), s.schema.end(), [](const ParamField& f) {
    return f.key.rfind(std::string(ParamFile::kBoardSection) + "/", 0) != 0;
  });
  return s;
}

std::string formatNumber(double v) {
  std::ostringstream o;
  o << v;
  return o.str();
}

std::string renderSchema(const Shipped& s) {
  std::string out = "| key | kind | accepted | unit |\n|---|---|---|---|\n";
  for (const ParamField& f : s.schema) {
    std::string kind, accepted;
    const std::string range = "[" + formatNumber(f.lo) + ", " + formatNumber(f.hi) + "]";
    switch (f.kind) {
      case ParamField::Kind::kNumber: kind = "number"; accepted = range; break;
      case ParamField::Kind::kInteger: kind = "integer"; accepted = range; break;
      case ParamField::Kind::kNumbers: kind = std::to_string(f.count) + " numbers"; accepted = "each in " + range; break;
      case ParamField::Kind::kText: kind = "text"; accepted = "-"; break;
    }
    if (!f.required) kind += ", optional";
    out += "| `" + f.key + "` | " + kind + " | " + accepted + " | " + (f.unit.empty() ? "-" : f.unit) + " |\n";
  }
  return out;
}

// The error a load of this text raises (nullopt when it loads). Any exception other than
// uhaptics::Error escapes and fails the test case.
std::optional<std::string> loadError(const DeviceDefinition& d, const std::string& text, const std::string& origin) {
  try {
    boardSpecFromParams(d, ParamFile::parse(text, origin));
  } catch (const Error& e) {
    return std::string(e.what());
  }
  return std::nullopt;
}

json::json_pointer pointerTo(const std::string& key) { return json::json_pointer("/" + key); }

// The value node of a field: the "value" of a documented entry, or the bare value.
json& valueOf(json& doc, const std::string& key) {
  json& node = doc.at(pointerTo(key));
  return node.is_object() && node.contains("value") ? node["value"] : node;
}

// key with two neighbouring letters of its last component swapped (a typo one edit away).
std::string misspelt(const std::string& key) {
  std::string out = key;
  const std::size_t start = key.rfind('/') == std::string::npos ? 0 : key.rfind('/') + 1;
  for (std::size_t i = start + (key.size() - start) / 2; i + 1 < key.size(); ++i) {
    if (out[i] != out[i + 1]) {
      std::swap(out[i], out[i + 1]);
      return out;
    }
  }
  for (std::size_t i = start; i + 1 < key.size(); ++i)
    if (out[i] != out[i + 1]) return std::swap(out[i], out[i + 1]), out;
  return out + "x";
}

}  // namespace

TEST_CASE("docs/parameter-files.md shows each device's schema as its loaders read it", "[backends][params]") {
  const std::string doc_path = std::string(UHAPTICS_SOURCE_DIR) + "/docs/parameter-files.md";
  std::string doc = readText(doc_path);
  REQUIRE_FALSE(doc.empty());
  std::string expected;
  for (const DeviceDefinition* d : deviceDefinitions()) {
    const Shipped s = shipped(*d);
    expected += "\n### " + d->name + ": `" + d->params_file + "` (" + d->title + ")\n\n" + renderSchema(s);
  }
  const std::string begin = "<!-- begin generated: parameter-schemas -->\n";
  const std::string end = "\n<!-- end generated: parameter-schemas -->";
  const std::size_t b = doc.find(begin), e = doc.find(end);
  REQUIRE(b != std::string::npos);
  REQUIRE(e != std::string::npos);
  const bool stale = doc.substr(b + begin.size(), e - b - begin.size()) != expected;
  // UHAPTICS_UPDATE_DOCS=1 rewrites the tables in the source tree after a schema change.
  if (stale && std::getenv("UHAPTICS_UPDATE_DOCS") != nullptr) {
    doc.replace(b + begin.size(), e - b - begin.size(), expected);
    std::ofstream(doc_path) << doc;
    WARN("rewrote the generated tables of " << doc_path);
    return;
  }
  INFO("the tables differ from the loaders' schema; run this test with UHAPTICS_UPDATE_DOCS=1 to rewrite them");
  CHECK_FALSE(stale);
}

TEST_CASE("every field of every shipped parameter file: bad inputs are refused naming the file and the field",
          "[backends][params]") {
  std::size_t cases = 0;
  const auto expectRefused = [&](const Shipped& s, const std::string& text, const std::string& what,
                                 const std::vector<std::string>& keys, bool out_of_range = false) {
    ++cases;
    INFO(s.device->name << ": " << what);
    const auto error = loadError(*s.device, text, s.path);
    REQUIRE(error.has_value());
    CHECK_THAT(*error, Catch::Matchers::Contains(s.path));
    for (const auto& k : keys) CHECK_THAT(*error, Catch::Matchers::Contains("'" + k));
    if (out_of_range) CHECK_THAT(*error, Catch::Matchers::Contains("outside"));
  };
  const json inf_marker = "@@1e999@@";
  const auto withInfinity = [&](const json& doc) {
    std::string text = doc.dump(1);
    const std::string quoted = inf_marker.dump();
    text.replace(text.find(quoted), quoted.size(), "1e999");  // JSON's own writer cannot write it
    return text;
  };

  for (const DeviceDefinition* d : deviceDefinitions()) {
    const Shipped s = shipped(*d);
    REQUIRE_FALSE(s.schema.empty());
    const json original = json::parse(s.text);
    REQUIRE_FALSE(loadError(*d, s.text, s.path).has_value());
    std::set<std::string> sections{""};

    for (const ParamField& f : s.schema) {
      const std::size_t slash = f.key.rfind('/');
      const std::string parent = slash == std::string::npos ? "" : f.key.substr(0, slash);
      const std::string name = slash == std::string::npos ? f.key : f.key.substr(slash + 1);
      sections.insert(parent);
      const auto mutated = [&](const auto& change) {
        json doc = original;
        change(doc);
        return doc;
      };
      const auto parentOf = [&](json& doc) -> json& { return parent.empty() ? doc : doc.at(pointerTo(parent)); };

      // Missing: refused when required; an optional field takes the loader's default.
      const json without = mutated([&](json& doc) { parentOf(doc).erase(name); });
      if (f.required) {
        expectRefused(s, without.dump(), "missing " + f.key, {f.key});
      } else {
        ++cases;
        CHECK_FALSE(loadError(*d, without.dump(), s.path).has_value());
      }

      // Misspelt: the message names the misspelling and the key meant.
      const std::string typo = misspelt(name);
      const json renamed = mutated([&](json& doc) {
        json& p = parentOf(doc);
        p[typo] = p[name];
        p.erase(name);
      });
      const std::string typo_key = parent.empty() ? typo : parent + "/" + typo;
      expectRefused(s, renamed.dump(), "misspelt " + typo_key, {typo_key, f.key});

      // Wrong types, a number beyond a double, values below and above the range.
      std::vector<json> wrong{json::array({1.0, 2.0}), json::object(), nullptr};
      if (f.kind != ParamField::Kind::kText) wrong.push_back("x");
      if (f.kind == ParamField::Kind::kNumbers) wrong.front() = 1.0;
      if (f.kind == ParamField::Kind::kInteger) wrong.push_back(0.5);
      for (const json& w : wrong)
        expectRefused(s, mutated([&](json& doc) { valueOf(doc, f.key) = w; }).dump(),
                      f.key + " = " + w.dump(), {f.key});
      const auto setFirst = [&](json& doc, const json& v) {
        json& value = valueOf(doc, f.key);
        (f.kind == ParamField::Kind::kNumbers ? value[0] : value) = v;
      };
      expectRefused(s, withInfinity(mutated([&](json& doc) { setFirst(doc, inf_marker); })), f.key + " = 1e999",
                    {f.key});
      if (f.kind == ParamField::Kind::kText) continue;
      json below = f.lo - std::max(1.0, std::abs(f.lo)), above = f.hi + std::max(1.0, std::abs(f.hi));
      if (f.kind == ParamField::Kind::kInteger)
        below = static_cast<long>(f.lo) - 1, above = static_cast<long>(f.hi) + 1;
      for (const json& v : {below, above})
        expectRefused(s, mutated([&](json& doc) { setFirst(doc, v); }).dump(), f.key + " = " + v.dump(),
                      {f.key}, true);
    }
    // A key nobody reads, at the top and in every section the loaders read.
    for (const std::string& section : sections) {
      const std::string key = section.empty() ? "no_such_field" : section + "/no_such_field";
      json doc = original;
      doc[pointerTo(key)] = 1.0;
      expectRefused(s, doc.dump(), "unknown " + key, {key});
    }
    // A folder given as the parameter file.
    ++cases;
    CHECK_THROWS_WITH(ParamFile::load(UHAPTICS_PARAMS_DIR), Catch::Matchers::Contains("is a folder"));
  }
  WARN("parameter files: " << cases << " bad-input cases tried");
  CHECK(cases > 500);
}
