// Where the parameter files are found: the environment first, in the build tree the build's own
// folder, <build>/share/uhaptics/params, which CMake assembles from the device folders (this test
// program, in <build>/tests, finds it beside itself). An installed program finds
// <prefix>/share/uhaptics/params: see params_location.hpp.
#include <catch2/catch.hpp>

#include <cstdlib>
#include <filesystem>
#include <set>
#include <string>

#include "params.hpp"
#include "uhaptics/backends/device_definition.hpp"
#include "uhaptics/backends/params_location.hpp"

namespace fs = std::filesystem;

TEST_CASE("the parameter folder: UHAPTICS_PARAMS_DIR first, else the build's own", "[backends][params]") {
  ::unsetenv("UHAPTICS_PARAMS_DIR");
  CHECK(fs::equivalent(uhaptics::defaultParamsDirectory(), UHAPTICS_PARAMS_DIR));  // this test runs in the build tree
  ::setenv("UHAPTICS_PARAMS_DIR", "/lab/params", 1);
  CHECK(uhaptics::defaultParamsDirectory() == "/lab/params");
  ::setenv("UHAPTICS_PARAMS_DIR", "", 1);  // empty counts as unset
  CHECK(fs::equivalent(uhaptics::defaultParamsDirectory(), UHAPTICS_PARAMS_DIR));
  ::unsetenv("UHAPTICS_PARAMS_DIR");
}

TEST_CASE("the build's parameter folder is the device folders' parameter files, as they are", "[backends][params]") {
  // Every devices/<folder>/params/*.json, copied unchanged, and nothing else.
  std::set<std::string> sources;
  for (const auto& folder : fs::directory_iterator(fs::path(UHAPTICS_SOURCE_DIR) / "devices")) {
    const fs::path params = folder.path() / "params";
    if (!fs::is_directory(params)) continue;
    for (const auto& file : fs::directory_iterator(params)) {
      if (file.path().extension() != ".json") continue;
      const std::string name = file.path().filename().string();
      INFO(file.path().string());
      CHECK(sources.insert(name).second);  // one file per name
      CHECK(uhaptics::test::readFile(uhaptics::test::paramsPath(name)) == uhaptics::test::readFile(file.path().string()));
    }
  }
  std::set<std::string> copies;
  for (const auto& file : fs::directory_iterator(UHAPTICS_PARAMS_DIR)) copies.insert(file.path().filename().string());
  CHECK(copies == sources);
  // Each registered device's file, and paper 003's example arm (loaded by the RHI's experiments).
  for (const uhaptics::DeviceDefinition* device : uhaptics::deviceDefinitions()) CHECK(copies.count(device->params_file) == 1);
  CHECK(copies.count("planar3.json") == 1);
}
