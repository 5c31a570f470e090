// uhaptics-report: gathers every experiment's reproduction.csv under an output folder into
// REPORT.md (tables + figures) and reproduction.csv, and prints the combined table.
// Exit status 0 when every check passes or needs data the papers do not publish, 1 when any other
// check fails, 2 on a usage or I/O error.
#include <CLI/CLI.hpp>
#include <fstream>
#include <iostream>

#include "uhaptics/experiments/report.hpp"

int main(int argc, char** argv) {
  CLI::App app{"Collect the reproduction tables of all experiments into one report"};
  std::string root = "out";
  std::vector<std::string> meta;
  app.add_option("--out", root, "Output folder holding one sub-folder per experiment")->capture_default_str();
  app.add_option("--meta", meta, "Run metadata as key=value (repeatable), shown at the top of the report");
  CLI11_PARSE(app, argc, argv);
  try {
    const auto experiments = uhaptics::experiments::collectExperiments(root);
    if (experiments.empty()) {
      std::cerr << "uhaptics-report: no */reproduction.csv under '" << root << "'\n";
      return 2;
    }
    std::vector<std::pair<std::string, std::string>> metadata;
    for (const auto& kv : meta) {
      const auto eq = kv.find('=');
      if (eq == std::string::npos) {
        std::cerr << "uhaptics-report: --meta expects key=value, got '" << kv << "'\n";
        return 2;
      }
      metadata.emplace_back(kv.substr(0, eq), kv.substr(eq + 1));
    }
    const std::string path = root + "/REPORT.md";
    std::ofstream(path) << uhaptics::experiments::renderMarkdown(experiments, metadata);
    uhaptics::experiments::ReproductionTable all;
    for (const auto& e : experiments)
      for (const auto& r : e.table.rows()) all.add(r);
    all.writeCsv(root + "/reproduction.csv");
    std::cout << "\n" << all.format() << "\n";
    std::size_t passed = 0, failed = 0;
    for (const auto& r : all.rows()) {
      passed += r.pass ? 1 : 0;
      failed += r.fails() ? 1 : 0;
    }
    const std::size_t needs_data = all.rows().size() - passed - failed;
    std::cout << passed << " of " << all.rows().size() << " checks pass, " << failed << " fail, " << needs_data
              << " need data the papers do not publish (not a failure); report: " << path << "\n";
    return failed == 0 ? 0 : 1;
  } catch (const std::exception& e) {
    std::cerr << "uhaptics-report: " << e.what() << "\n";
    return 2;
  }
}
