#pragma once
// The reproduction table under the tools' namespace, for tools/servo/main.cpp, which names it
// uhaptics::tools::ReproductionTable. The table belongs to the experiments library
// (uhaptics/experiments/reproduction.hpp, linked into every tool by uhaptics_add_tool); include that
// header in new code.
#include "uhaptics/experiments/reproduction.hpp"

namespace uhaptics::tools {
using experiments::ReproductionRow;
using experiments::ReproductionTable;
using experiments::resultWord;
}  // namespace uhaptics::tools
