#include "uhaptics/backends/params_location.hpp"

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <string>
#include <sys/stat.h>

// Defined (strong) only in programs linked against an installed uhaptics, by the source file its
// CMake package adds to them; absent (null) in the build tree.
extern "C" __attribute__((weak)) const char* const uhaptics_installed_params_dir;

namespace uhaptics {
namespace {

bool isDirectory(const std::string& path) {
  struct stat info {};
  return ::stat(path.c_str(), &info) == 0 && S_ISDIR(info.st_mode);
}

std::string programFolder() {
  char buffer[4096];
  const ssize_t n = ::readlink("/proc/self/exe", buffer, sizeof buffer - 1);
  if (n <= 0) return {};
  const std::string exe(buffer, static_cast<std::size_t>(n));
  const auto slash = exe.rfind('/');
  return slash == std::string::npos ? std::string() : exe.substr(0, slash);
}

}  // namespace

std::string defaultParamsDirectory() {
  const char* env = std::getenv("UHAPTICS_PARAMS_DIR");
  if (env != nullptr && *env != '\0') return env;
  const std::string folder = programFolder();
  // The program's folder comes resolved from /proc/self/exe (no symbolic links), so dropping ".."
  // lexically names the same folder.
  const std::string beside = folder + "/../share/uhaptics/params";
  if (!folder.empty() && isDirectory(beside)) return std::filesystem::path(beside).lexically_normal().string();
  if (&uhaptics_installed_params_dir != nullptr && uhaptics_installed_params_dir != nullptr)
    return uhaptics_installed_params_dir;
  return UHAPTICS_PARAMS_DIR;
}

}  // namespace uhaptics
