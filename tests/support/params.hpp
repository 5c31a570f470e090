#pragma once
// The parameter files the devices ship with (the build's parameter folder, assembled from
// devices/<folder>/params/; tests/CMakeLists.txt passes it as UHAPTICS_PARAMS_DIR), and whole-file
// reads for tests that inspect or edit a file's text.
#include <fstream>
#include <sstream>
#include <string>

namespace uhaptics::test {

/// <build>/share/uhaptics/params.
inline std::string paramsDir() { return UHAPTICS_PARAMS_DIR; }

/// A file in the parameter folder, e.g. paramsPath("tau.json").
inline std::string paramsPath(const std::string& file) { return paramsDir() + "/" + file; }

/// The whole text of a file ("" when it cannot be read).
inline std::string readFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace uhaptics::test
