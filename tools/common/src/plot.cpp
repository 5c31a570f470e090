#include "uhaptics/tools/plot.hpp"

#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <stdexcept>

#ifndef UHAPTICS_PLOTS_DIR
#error "UHAPTICS_PLOTS_DIR must be defined by the build"
#endif

namespace uhaptics::tools {

namespace {
std::string quote(const std::string& s) {
  std::string out = "'";
  for (char c : s) {
    if (c == '\'') out += "'\\''";
    else out += c;
  }
  return out + "'";
}
}  // namespace

std::string plotsDirectory() {
  if (const char* env = std::getenv("UHAPTICS_PLOTS_DIR")) return env;
  return UHAPTICS_PLOTS_DIR;
}

void ensureDirectory(const std::string& path) {
  std::error_code ec;
  std::filesystem::create_directories(path, ec);
  if (ec) throw std::runtime_error(path + ": cannot create folder (" + ec.message() + ")");
}

bool runPlotScript(const std::string& script, const std::vector<std::string>& args) {
  const std::string path = plotsDirectory() + "/" + script;
  if (!std::filesystem::exists(path)) {
    std::cerr << "plot: " << path << " not found; figure skipped\n";
    return false;
  }
  // Debian's interpreter carries python3-matplotlib; a python3 earlier on PATH may not.
  const char* python = std::filesystem::exists("/usr/bin/python3") ? "/usr/bin/python3" : "python3";
  std::string cmd = std::string(python) + " " + quote(path);
  for (const auto& a : args) cmd += " " + quote(a);
  const int rc = std::system(cmd.c_str());
  if (rc != 0) {
    std::cerr << "plot: '" << script << "' failed (exit " << rc
              << "); is python3-matplotlib installed? The CSV files are complete.\n";
    return false;
  }
  return true;
}

}  // namespace uhaptics::tools
