// uhaptics-report: gathers every experiment's reproduction.csv under an output folder into
// REPORT.md (tables + figures) and reproduction.csv, and prints the combined table. With
// --update-doc it also rewrites the generated regions of Markdown files (the docs' tables, between
// '<!-- begin generated: NAME -->' and '<!-- end generated: NAME -->' lines) from those tables and
// from Google Benchmark's JSON (--bench-json), leaving the rest of each file as it is.
//   uhaptics-report --out out --update-doc docs/reproduction.md
//   uhaptics-report --bench-json out/bench/bench.json --update-doc docs/benchmarks.md
// Exit status 0 when every check passes or needs data the papers do not publish, 1 when any other
// check fails, 2 on a usage or I/O error (a file to update without markers, a region this run
// cannot make).
#include <CLI/CLI.hpp>
#include <fstream>
#include <iostream>
#include <sstream>

#include "uhaptics/experiments/report.hpp"
#include "uhaptics/tools/cli.hpp"

namespace {
std::string readFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot read");
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Collect the reproduction tables of all experiments into one report"};
  std::string root = "out";
  std::string bench_json;
  std::vector<std::string> meta;
  std::vector<std::string> docs;
  app.footer("Exit status: 0 every check passes or needs unpublished data; 1 a check fails; 2 a usage or I/O "
             "error or a malformed reproduction.csv; 101/105 a refused command-line value.");
  uhaptics::tools::CommandLine cli(app, "uhaptics-report");
  cli.inputFolder("--out", root, "Output folder holding one sub-folder per experiment")->capture_default_str();
  cli.texts("--meta", meta, "Run metadata as key=value (repeatable), shown at the top of the report");
  cli.inputFile("--bench-json", bench_json,
                "Google Benchmark's JSON output (uhaptics-bench --benchmark_out=F --benchmark_out_format=json): "
                "the bench-* regions");
  cli.inputFiles("--update-doc", docs,
                 "Markdown file whose generated regions to rewrite (repeatable); refused without markers");
  if (const int status = cli.parse(argc, argv); status >= 0) return status;
  try {
    std::vector<std::pair<std::string, std::string>> metadata;
    for (const auto& kv : meta) {
      const auto eq = kv.find('=');
      if (eq == std::string::npos) {
        std::cerr << "uhaptics-report: --meta expects key=value, got '" << kv << "'\n";
        return 2;
      }
      metadata.emplace_back(kv.substr(0, eq), kv.substr(eq + 1));
    }
    const auto experiments = uhaptics::experiments::collectExperiments(root);
    if (experiments.empty() && bench_json.empty()) {
      std::cerr << "uhaptics-report: no */reproduction.csv under '" << root << "'\n";
      return 2;
    }
    uhaptics::experiments::GeneratedRegions regions;
    std::size_t failed = 0;
    if (!experiments.empty()) {
      const std::string path = root + "/REPORT.md";
      std::ofstream report(path, std::ios::trunc);
      if (!(report << uhaptics::experiments::renderMarkdown(experiments, metadata)))
        throw std::runtime_error(path + ": cannot write");
      uhaptics::experiments::ReproductionTable all;
      for (const auto& e : experiments)
        for (const auto& r : e.table.rows()) all.add(r);
      all.writeCsv(root + "/reproduction.csv");
      std::cout << "\n" << all.format() << "\n";
      std::cout << all.recheckableRows() << " of " << all.rows().size()
                << " rows decided again from their numbers (the others join several numbers in one verdict)\n";
      std::size_t passed = 0;
      for (const auto& r : all.rows()) {
        passed += r.pass ? 1 : 0;
        failed += r.fails() ? 1 : 0;
      }
      const std::size_t needs_data = all.rows().size() - passed - failed;
      std::cout << passed << " of " << all.rows().size() << " checks pass, " << failed << " fail, " << needs_data
                << " need data the papers do not publish (not a failure); report: " << path << "\n";
      regions = uhaptics::experiments::reproductionRegions(experiments, metadata);
    }
    if (!bench_json.empty())
      for (auto& [name, content] : uhaptics::experiments::benchmarkRegions(readFile(bench_json), metadata))
        regions[name] = content;
    // Every file is checked before any is written: a refused file leaves all of them as they were.
    std::vector<std::pair<std::string, std::string>> rewritten;
    for (const auto& doc : docs)
      rewritten.emplace_back(doc, uhaptics::experiments::rewriteGeneratedRegions(readFile(doc), regions, doc));
    for (const auto& [doc, text] : rewritten) {
      std::ofstream out(doc, std::ios::binary | std::ios::trunc);
      if (!(out << text)) throw std::runtime_error(doc + ": cannot write");
      std::cout << "uhaptics-report: rewrote the generated regions of " << doc << "\n";
    }
    return failed == 0 ? 0 : 1;
  } catch (const std::exception& e) {
    std::cerr << "uhaptics-report: " << e.what() << "\n";
    return 2;
  }
}
