#pragma once
// The reproduction report: every experiment folder under an output root holds a reproduction.csv
// (and its figures); the report gathers them into one Markdown page and one terminal table. The
// same figures fill the docs' generated tables: a Markdown file marks each with the lines
//
//   <!-- begin generated: NAME -->
//   <!-- end generated: NAME -->
//
// and rewriteGeneratedRegions() replaces what lies between them, leaving the rest of the file as
// written by hand.
#include <map>
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

using Metadata = std::vector<std::pair<std::string, std::string>>;

/// Experiments found below root (one level deep), sorted by the paper of their first row, then name.
std::vector<ExperimentResult> collectExperiments(const std::string& root);

/// Self-contained Markdown: metadata, the overall verdict, per-experiment tables and figures.
std::string renderMarkdown(const std::vector<ExperimentResult>& experiments, const Metadata& metadata);

/// The heading of a paper's rows, "Paper 001 — <title> (<citation>)", from the device definition
/// that reproduces it (DeviceDefinition::paper, the one place a paper's title is written);
/// "chai3d" heads the rows of CHAI3D's unchanged examples; an id no device has reads "Paper <id>".
std::string paperHeading(const std::string& paper);

/// Generated Markdown by region name.
using GeneratedRegions = std::map<std::string, std::string>;

/// "reproduction-summary" (per paper: its title, the devices reproducing it, the checks' results)
/// and "reproduction" (every row, grouped by paper), headed by the run's metadata.
GeneratedRegions reproductionRegions(const std::vector<ExperimentResult>& experiments, const Metadata& metadata);

/// From Google Benchmark's JSON (--benchmark_format=json or --benchmark_out_format=json), every
/// iteration run: "bench-ticks" (each benchmark with an allocs_per_tick or allocs_per_step counter,
/// the servo ticks: CPU time, allocations, calls per 1 ms budget) and "bench-time-vs-error" (each
/// benchmark family with an error counter: time and error per swept value, defaults in bold).
/// Throws std::runtime_error naming what is missing in a file that is not such JSON.
GeneratedRegions benchmarkRegions(const std::string& json_text, const Metadata& metadata);

/// Names of the generated regions of a Markdown text, in order (throws like the rewrite on broken
/// markers).
std::vector<std::string> generatedRegionNames(const std::string& markdown);

/// The Markdown text with the lines between each region's begin and end markers replaced by that
/// region's content; every other byte is kept. Throws std::runtime_error (message starting with
/// `name`) when the text has no generated region, a region lacks its end marker, regions nest or
/// repeat, or a region is not among `regions` (the message lists the ones this run can make).
std::string rewriteGeneratedRegions(const std::string& markdown, const GeneratedRegions& regions,
                                    const std::string& name);

}  // namespace uhaptics::experiments
