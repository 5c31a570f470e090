#pragma once
// Where the device parameter files are when nobody says: the first of
//   1. $UHAPTICS_PARAMS_DIR, when set and not empty;
//   2. <folder of the running program>/../share/uhaptics/params, when it exists (an installed tool,
//      or an application installed into uhaptics' prefix);
//   3. the installed folder <prefix>/share/uhaptics/params, for programs built against an installed
//      uhaptics (its CMake package compiles the location into them: params_location.cpp.in);
//   4. devices/params in the source tree this library was built from (programs in the build tree).
#include <string>

namespace uhaptics {

std::string defaultParamsDirectory();

}  // namespace uhaptics
