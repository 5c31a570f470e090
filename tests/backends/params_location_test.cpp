// Where the parameter files are found: the environment first, in the build tree the source tree's
// folder. (An installed program finds <prefix>/share/uhaptics/params: see params_location.hpp.)
#include <catch2/catch.hpp>

#include <cstdlib>

#include "uhaptics/backends/params_location.hpp"

TEST_CASE("the parameter folder: UHAPTICS_PARAMS_DIR first, else the build's own", "[backends][params]") {
  ::unsetenv("UHAPTICS_PARAMS_DIR");
  CHECK(uhaptics::defaultParamsDirectory() == UHAPTICS_PARAMS_DIR);  // this test runs in the build tree
  ::setenv("UHAPTICS_PARAMS_DIR", "/lab/params", 1);
  CHECK(uhaptics::defaultParamsDirectory() == "/lab/params");
  ::setenv("UHAPTICS_PARAMS_DIR", "", 1);  // empty counts as unset
  CHECK(uhaptics::defaultParamsDirectory() == UHAPTICS_PARAMS_DIR);
  ::unsetenv("UHAPTICS_PARAMS_DIR");
}
