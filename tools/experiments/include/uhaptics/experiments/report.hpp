#pragma once
// The reproduction report: every experiment folder under an output root holds a reproduction.csv
// (and its figures); the report gathers them into one Markdown page and one terminal table.
#include <string>
#include <utility>
#include <vector>

#include "uhaptics/experiments/reproduction.hpp"

namespace uhaptics::experiments {

struct ExperimentResult {
  std::string folder;                // relative to the output root, e.g. "exo-fig4"
  ReproductionTable table;
  std::vector<std::string> figures;  // PNG files relative to the output root, sorted
  std::string summary;               // summary.txt of the experiment, if it wrote one
};

/// Experiments found below root (one level deep), sorted by the paper of their first row, then name.
std::vector<ExperimentResult> collectExperiments(const std::string& root);

/// Self-contained Markdown: metadata, the overall verdict, per-experiment tables and figures.
std::string renderMarkdown(const std::vector<ExperimentResult>& experiments,
                           const std::vector<std::pair<std::string, std::string>>& metadata);

}  // namespace uhaptics::experiments
