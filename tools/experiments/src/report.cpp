#include "uhaptics/experiments/report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace fs = std::filesystem;

namespace uhaptics::experiments {

namespace {
std::string fmt(double v) {
  if (std::isnan(v)) return "—";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", v);
  return buf;
}

std::string paperTitle(const std::string& paper) {
  if (paper == "000") return "Paper 000 — subspace proxy for an underactuated finger exoskeleton";
  if (paper == "001") return "Paper 001 — LQR position-control wall on the TAU device";
  if (paper == "003") return "Paper 003 — force-manipulability null-space control of a redundant interface";
  if (paper == "chai3d") return "The plugin in CHAI3D — CHAI3D's own examples, unchanged, with each device";
  return "Paper " + paper;
}

std::string markdownCell(std::string s) {
  std::string out;
  for (char c : s) out += (c == '|') ? std::string("\\|") : std::string(1, c);
  return out;
}
}  // namespace

std::vector<ExperimentResult> collectExperiments(const std::string& root) {
  std::vector<ExperimentResult> out;
  if (!fs::is_directory(root)) return out;
  for (const auto& entry : fs::directory_iterator(root)) {
    if (!entry.is_directory()) continue;
    const fs::path csv = entry.path() / "reproduction.csv";
    if (!fs::exists(csv)) continue;
    ExperimentResult r;
    r.folder = entry.path().filename().string();
    r.table = ReproductionTable::readCsv(csv.string());
    for (const auto& f : fs::recursive_directory_iterator(entry.path()))
      if (f.is_regular_file() && f.path().extension() == ".png")
        r.figures.push_back(fs::relative(f.path(), root).generic_string());
    std::sort(r.figures.begin(), r.figures.end());
    const fs::path summary = entry.path() / "summary.txt";
    if (fs::exists(summary)) {
      std::ifstream in(summary);
      std::stringstream ss;
      ss << in.rdbuf();
      r.summary = ss.str();
    }
    out.push_back(std::move(r));
  }
  auto paperOf = [](const ExperimentResult& e) {
    return e.table.rows().empty() ? std::string("999") : e.table.rows().front().paper;
  };
  std::sort(out.begin(), out.end(), [&](const ExperimentResult& a, const ExperimentResult& b) {
    return std::make_pair(paperOf(a), a.folder) < std::make_pair(paperOf(b), b.folder);
  });
  return out;
}

std::string renderMarkdown(const std::vector<ExperimentResult>& experiments,
                           const std::vector<std::pair<std::string, std::string>>& metadata) {
  std::size_t rows = 0, passed = 0, needs_data = 0;
  for (const auto& e : experiments)
    for (const auto& r : e.table.rows()) {
      ++rows;
      passed += r.pass ? 1 : 0;
      needs_data += (!r.pass && !r.needs_data.empty()) ? 1 : 0;
    }
  std::ostringstream md;
  md << "# uhaptics reproduction report\n\n";
  md << "**" << passed << " of " << rows << " checks pass** across " << experiments.size() << " experiments";
  if (needs_data > 0) md << "; " << needs_data << " cannot be decided without data the papers do not publish";
  md << ".\n\n";
  if (!metadata.empty()) {
    md << "| run | |\n|---|---|\n";
    for (const auto& [k, v] : metadata) md << "| " << markdownCell(k) << " | " << markdownCell(v) << " |\n";
    md << "\n";
  }
  std::string current_paper;
  for (const auto& e : experiments) {
    const std::string paper = e.table.rows().empty() ? "" : e.table.rows().front().paper;
    if (paper != current_paper) {
      md << "## " << paperTitle(paper) << "\n\n";
      current_paper = paper;
    }
    md << "### " << e.folder << "\n\n";
    md << "| quantity | published | measured | unit | criterion | result |\n|---|---:|---:|---|---|---|\n";
    for (const auto& r : e.table.rows())
      md << "| " << markdownCell(r.quantity) << " | " << fmt(r.published) << " | " << fmt(r.measured) << " | "
         << markdownCell(r.unit) << " | " << markdownCell(r.criterion) << " | "
         << (r.pass ? "pass" : r.needs_data.empty() ? "**FAIL**" : "needs data") << " |\n";
    md << "\n";
    for (const auto& r : e.table.rows())
      if (!r.pass && !r.needs_data.empty())
        md << "- **needs data** — " << markdownCell(r.quantity) << ": " << r.needs_data << "\n";
    md << "\n";
    if (!e.summary.empty()) md << "```\n" << e.summary << (e.summary.back() == '\n' ? "" : "\n") << "```\n\n";
    for (const auto& f : e.figures) md << "![" << f << "](" << f << ")\n\n";
  }
  return md.str();
}

}  // namespace uhaptics::experiments
