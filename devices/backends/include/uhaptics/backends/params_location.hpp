#pragma once
// Where the device parameter files are when nobody says: the first of
//   1. $UHAPTICS_PARAMS_DIR, when set and not empty;
//   2. <folder of the running program>/../share/uhaptics/params, when it exists (an installed tool,
//      an application installed into uhaptics' prefix, or a program one folder below the build
//      folder, such as the test suites in <build>/tests);
//   3. the installed folder <prefix>/share/uhaptics/params, for programs built against an installed
//      uhaptics (its CMake package adds <prefix>/share/uhaptics/params_location.cpp to them, which
//      devices/backends/CMakeLists.txt writes);
//   4. the parameter folder of the build this library was built in, <build>/share/uhaptics/params,
//      which CMake assembles from the device folders' params/*.json (programs in the build tree).
// Case 2 returns the folder without its "..", e.g. <build>/share/uhaptics/params for <build>/tests.
#include <string>

namespace uhaptics {

std::string defaultParamsDirectory();

}  // namespace uhaptics
