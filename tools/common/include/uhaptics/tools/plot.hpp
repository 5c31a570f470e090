#pragma once
// Figures are drawn by small matplotlib scripts in tools/plots, run with Debian's /usr/bin/python3.
#include <string>
#include <vector>

namespace uhaptics::tools {

/// Runs tools/plots/<script> with args. Returns false (and says why on stderr) when the figure
/// could not be made; the CSV the figure is drawn from is written regardless.
bool runPlotScript(const std::string& script, const std::vector<std::string>& args);

/// Folder of the plotting scripts (UHAPTICS_PLOTS_DIR in the environment overrides the default).
std::string plotsDirectory();

/// Creates the folder (and parents) if needed; throws std::runtime_error when it cannot.
void ensureDirectory(const std::string& path);

}  // namespace uhaptics::tools
