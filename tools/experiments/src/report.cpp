#include "uhaptics/experiments/report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <cctype>
#include <cstring>
#include <set>
#include <sstream>
#include <stdexcept>

#include "uhaptics/backends/device_definition.hpp"

namespace fs = std::filesystem;

namespace uhaptics::experiments {

namespace {
std::string fmt(double v) {
  if (std::isnan(v)) return "—";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", v);
  return buf;
}

// The rows of CHAI3D's unchanged examples (examples/chai3d-unchanged/run_examples.py) carry this
// in their paper column: they test the plugin, not a paper.
constexpr const char* kChai3dRows = "chai3d";

std::string markdownCell(std::string s) {
  std::string out;
  for (char c : s) out += (c == '|') ? std::string("\\|") : std::string(1, c);
  return out;
}
}  // namespace

std::string paperHeading(const std::string& paper) {
  if (paper == kChai3dRows) return "The plugin in CHAI3D — CHAI3D's own examples, unchanged, with each device";
  if (paper == kStabilityRows)
    return "Stability — the Z-width of each device (Colgate and Brown 1994) and the passivity layer (Hannaford and "
           "Ryu 2002)";
  if (const DeviceDefinition* d = findDeviceByPaper(paper))
    return "Paper " + paper + " — " + d->paper.title + (d->paper.citation.empty() ? "" : " (" + d->paper.citation + ")");
  return "Paper " + paper;
}

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

std::string renderMarkdown(const std::vector<ExperimentResult>& experiments, const Metadata& metadata) {
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
      md << "## " << paperHeading(paper) << "\n\n";
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

// ---- The docs' generated tables ----------------------------------------------------------------

namespace {

std::string joinMetadata(const Metadata& metadata) {
  std::string out;
  for (const auto& [k, v] : metadata) out += (out.empty() ? "" : ", ") + k + " " + v;
  return out;
}

// "000 *title*" for a paper with a device, the CHAI3D rows' name, else the id.
std::string paperCell(const std::string& paper) {
  if (paper == kChai3dRows) return "CHAI3D's unchanged examples";
  if (paper == kStabilityRows) return "Stability (Z-width, passivity layer)";
  if (const DeviceDefinition* d = findDeviceByPaper(paper)) return paper + " *" + markdownCell(d->paper.title) + "*";
  return paper;
}

std::string devicesOf(const std::string& paper) {
  if (paper == kChai3dRows || paper == kStabilityRows) return "every device";
  std::string out;
  for (const DeviceDefinition* d : deviceDefinitions())
    if (d->paper.id == paper) out += (out.empty() ? "" : ", ") + d->title + " (`" + d->name + "`)";
  return out;
}

std::string resultCell(const ReproductionRow& r) {
  return r.pass ? "pass" : r.needs_data.empty() ? "**FAIL**" : "needs data";
}

// Time per call, from nanoseconds: "0.541 us", "19.2 us", "142 us", "3.52 ms".
std::string timeText(double ns) {
  char buf[32];
  const double us = ns / 1e3;
  if (us < 1e3) std::snprintf(buf, sizeof buf, "%.3g us", us);
  else std::snprintf(buf, sizeof buf, "%.3g ms", us / 1e3);
  return buf;
}

// Counters as "%g", errors to two digits, call counts whole.
std::string counterText(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}
std::string errorText(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2g", v);
  return buf;
}
std::string wholeText(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.0f", v);
  return buf;
}

double nanosecondsPer(const std::string& unit) {
  if (unit == "ns") return 1.0;
  if (unit == "us") return 1e3;
  if (unit == "ms") return 1e6;
  if (unit == "s") return 1e9;
  throw std::runtime_error("benchmark JSON: unknown time_unit '" + unit + "'");
}

// A marker line: [blanks] "<!--" [blanks] ("begin" | "end") " generated:" [blanks] name [blanks] "-->"
// [blanks or CR], the name of [A-Za-z0-9_.-]+. Parsed by hand: GCC 12's sanitizer builds warn
// inside <regex> (maybe-uninitialized), and warnings are errors.
bool parseMarker(const std::string& line, std::string& kind, std::string& region) {
  std::size_t i = 0;
  const auto blanks = [&](const char* set) {
    while (i < line.size() && std::strchr(set, line[i]) != nullptr && line[i] != '\0') ++i;
  };
  const auto literal = [&](const std::string& word) {
    if (line.compare(i, word.size(), word) != 0) return false;
    i += word.size();
    return true;
  };
  blanks(" \t");
  if (!literal("<!--")) return false;
  blanks(" \t");
  if (literal("begin")) {
    kind = "begin";
  } else if (literal("end")) {
    kind = "end";
  } else {
    return false;
  }
  if (!literal(" generated:")) return false;
  blanks(" \t");
  const std::size_t start = i;
  while (i < line.size() && (std::isalnum(static_cast<unsigned char>(line[i])) != 0 || line[i] == '_' ||
                             line[i] == '.' || line[i] == '-'))
    ++i;
  if (i == start) return false;
  region = line.substr(start, i - start);
  blanks(" \t");
  if (!literal("-->")) return false;
  blanks(" \t\r");
  return i == line.size();
}

struct Region {
  std::string name;
  std::size_t content_begin;  // just after the begin marker's line
  std::size_t content_end;    // at the start of the end marker's line
};

std::vector<Region> findRegions(const std::string& text, const std::string& name) {
  std::vector<Region> regions;
  std::set<std::string> seen;
  bool open = false;
  Region current;
  std::size_t open_line = 0, line_number = 0;
  for (std::size_t pos = 0; pos < text.size();) {
    const std::size_t eol = text.find('\n', pos);
    const std::size_t next = eol == std::string::npos ? text.size() : eol + 1;
    const std::string line = text.substr(pos, (eol == std::string::npos ? text.size() : eol) - pos);
    ++line_number;
    std::string kind, region;
    if (parseMarker(line, kind, region)) {
      const std::string where = name + ":" + std::to_string(line_number) + ": ";
      if (kind == "begin") {
        if (open)
          throw std::runtime_error(where + "region '" + region + "' begins inside region '" + current.name +
                                   "' (line " + std::to_string(open_line) + "), which has not ended");
        if (!seen.insert(region).second) throw std::runtime_error(where + "region '" + region + "' appears twice");
        current = {region, next, 0};
        open = true;
        open_line = line_number;
      } else {
        if (!open || region != current.name)
          throw std::runtime_error(where + "end of region '" + region + "' without its begin marker");
        current.content_end = pos;
        regions.push_back(current);
        open = false;
      }
    }
    pos = next;
  }
  if (open)
    throw std::runtime_error(name + ":" + std::to_string(open_line) + ": region '" + current.name +
                             "' has no end marker '<!-- end generated: " + current.name + " -->'");
  return regions;
}

std::string regionList(const GeneratedRegions& regions) {
  std::string out;
  for (const auto& [k, v] : regions) out += (out.empty() ? "" : ", ") + k;
  return out.empty() ? "none: no reproduction.csv under --out and no --bench-json" : out;
}

}  // namespace

GeneratedRegions reproductionRegions(const std::vector<ExperimentResult>& experiments, const Metadata& metadata) {
  std::vector<ReproductionRow> rows;
  for (const auto& e : experiments)
    for (const auto& r : e.table.rows()) rows.push_back(r);
  if (rows.empty()) return {};
  std::stable_sort(rows.begin(), rows.end(),
                   [](const ReproductionRow& a, const ReproductionRow& b) { return a.paper < b.paper; });
  std::size_t passed = 0, failed = 0;
  for (const auto& r : rows) {
    passed += r.pass ? 1 : 0;
    failed += r.fails() ? 1 : 0;
  }
  std::ostringstream head;
  head << "Generated by `uhaptics-report --update-doc` from one run's `reproduction.csv` files"
       << (metadata.empty() ? "" : " (" + markdownCell(joinMetadata(metadata)) + ")") << ": **" << passed << " of "
       << rows.size() << " checks pass**, " << failed << " fail, " << rows.size() - passed - failed
       << " need data the papers do not publish.\n\n";

  std::ostringstream summary;
  summary << head.str() << "| paper | reproduced on | checks | pass | fail | needs data |\n|---|---|---:|---:|---:|---:|\n";
  for (std::size_t i = 0; i < rows.size();) {
    std::size_t j = i, pass = 0, fail = 0;
    for (; j < rows.size() && rows[j].paper == rows[i].paper; ++j) {
      pass += rows[j].pass ? 1 : 0;
      fail += rows[j].fails() ? 1 : 0;
    }
    summary << "| " << paperCell(rows[i].paper) << " | " << devicesOf(rows[i].paper) << " | " << j - i << " | "
            << pass << " | " << fail << " | " << j - i - pass - fail << " |\n";
    i = j;
  }

  std::ostringstream table;
  table << head.str() << "| paper | quantity | published | measured | unit | criterion | result |\n"
        << "|---|---|---:|---:|---|---|---|\n";
  for (const auto& r : rows)
    table << "| " << markdownCell(r.paper) << " | " << markdownCell(r.quantity) << " | " << fmt(r.published) << " | "
          << fmt(r.measured) << " | " << markdownCell(r.unit) << " | " << markdownCell(r.criterion) << " | "
          << resultCell(r) << " |\n";
  bool first = true;
  for (const auto& r : rows)
    if (!r.pass && !r.needs_data.empty()) {
      table << (first ? "\n" : "") << "- needs data: " << markdownCell(r.quantity) << ": " << r.needs_data << "\n";
      first = false;
    }
  return {{"reproduction-summary", summary.str()}, {"reproduction", table.str()}};
}

// BM_Chai3dTick/<device>/<contact|free>/<chai3d|uhaptics> (tools/bench/chai3d_tick_bench.cpp): per
// device, CHAI3D's tick on a still device of the same specification, and with the device behind the
// tool; the difference is the device's cost. Empty without such runs.
std::string chai3dTickTable(const nlohmann::json& data, const std::string& head) {
  struct Ticks {
    double ns[2][2] = {{-1.0, -1.0}, {-1.0, -1.0}};  // [contact, free][chai3d, uhaptics]
    double allocs[2][2] = {{0.0, 0.0}, {0.0, 0.0}};
  };
  std::vector<std::pair<std::string, Ticks>> devices;
  const std::string prefix = "BM_Chai3dTick/";
  for (const auto& b : data["benchmarks"]) {
    const std::string name = b.value("name", std::string());
    if (name.compare(0, prefix.size(), prefix) != 0 || b.value("error_occurred", false)) continue;
    if (b.value("run_type", std::string("iteration")) != "iteration") continue;
    std::vector<std::string> parts;
    std::stringstream split(name.substr(prefix.size()));
    for (std::string part; std::getline(split, part, '/');) parts.push_back(part);
    if (parts.size() != 3 || (parts[1] != "contact" && parts[1] != "free") || (parts[2] != "chai3d" && parts[2] != "uhaptics"))
      continue;
    if (!b.contains("cpu_time") || !b["cpu_time"].is_number())
      throw std::runtime_error("benchmark JSON: " + name + " has no cpu_time");
    auto it = std::find_if(devices.begin(), devices.end(), [&](const auto& d) { return d.first == parts[0]; });
    if (it == devices.end()) it = devices.insert(devices.end(), {parts[0], Ticks{}});
    const int where = parts[1] == "contact" ? 0 : 1, who = parts[2] == "chai3d" ? 0 : 1;
    it->second.ns[where][who] = b["cpu_time"].get<double>() * nanosecondsPer(b.value("time_unit", std::string("ns")));
    it->second.allocs[where][who] =
        b.contains("allocs_per_tick") && b["allocs_per_tick"].is_number() ? b["allocs_per_tick"].get<double>() : 0.0;
  }
  const auto percent = [](double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.0f %%", 100.0 * v);
    return std::string(buf);
  };
  std::ostringstream t;
  t << head << "| device | CHAI3D alone, contact / free | with the device, contact / free | device's cost in contact "
               "(share of CHAI3D's contact tick) | device's cost in free space (share of its cost in contact) | heap "
               "allocations per tick, CHAI3D alone / added by the device |\n"
    << "|---|---:|---:|---:|---:|---:|\n";
  std::size_t rows = 0;
  for (const auto& [device, tick] : devices) {
    bool complete = true;
    for (const auto& where : tick.ns)
      for (const double ns : where) complete = complete && ns > 0.0;
    if (!complete) continue;
    const double contact = tick.ns[0][1] - tick.ns[0][0];
    const double free = tick.ns[1][1] - tick.ns[1][0];
    const double chai3d_allocs = std::max(tick.allocs[0][0], tick.allocs[1][0]);
    const double added_allocs = std::max(tick.allocs[0][1] - tick.allocs[0][0], tick.allocs[1][1] - tick.allocs[1][0]);
    t << "| " << markdownCell(device) << " | " << timeText(tick.ns[0][0]) << " / " << timeText(tick.ns[1][0]) << " | "
      << timeText(tick.ns[0][1]) << " / " << timeText(tick.ns[1][1]) << " | " << timeText(contact) << " ("
      << percent(contact / tick.ns[0][0]) << ") | " << timeText(free) << " ("
      << (contact > 0.0 ? percent(free / contact) : std::string("-")) << ") | " << counterText(chai3d_allocs) << " / "
      << counterText(added_allocs) << " |\n";
    ++rows;
  }
  return rows > 0 ? t.str() : "";
}

GeneratedRegions benchmarkRegions(const std::string& json_text, const Metadata& metadata) {
  nlohmann::json data;
  try {
    data = nlohmann::json::parse(json_text);
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error(std::string("benchmark JSON does not parse: ") + e.what());
  }
  if (!data.is_object() || !data.contains("benchmarks") || !data["benchmarks"].is_array())
    throw std::runtime_error("not Google Benchmark's JSON (--benchmark_format=json): no \"benchmarks\" array");
  const auto& context = data.value("context", nlohmann::json::object());
  std::ostringstream head;
  head << "Generated by `uhaptics-report --bench-json` from Google Benchmark's JSON (run "
       << context.value("date", std::string("of unknown date")) << ", " << context.value("num_cpus", 0) << " CPUs at "
       << context.value("mhz_per_cpu", 0) << " MHz" << (metadata.empty() ? "" : "; " + markdownCell(joinMetadata(metadata)))
       << "). CPU time per call.\n\n";

  auto number = [](const nlohmann::json& b, const char* key, double& out) {
    if (!b.contains(key) || !b[key].is_number()) return false;
    out = b[key].get<double>();
    return true;
  };
  struct Curve {
    std::string family, curve, swept;
    std::vector<std::string> points;  // "value: time error", the default's in bold
  };
  std::vector<Curve> curves;
  std::ostringstream ticks;
  ticks << head.str() << "| benchmark | CPU time | heap allocations per call | calls per 1 ms budget |\n"
        << "|---|---:|---:|---:|\n";
  std::size_t tick_rows = 0;
  for (const auto& b : data["benchmarks"]) {
    if (b.value("run_type", std::string("iteration")) != "iteration" || b.value("error_occurred", false)) continue;
    const std::string name = b.value("name", std::string());
    double cpu = 0.0, allocs = 0.0, error = 0.0, is_default = 0.0;
    if (name.empty() || !number(b, "cpu_time", cpu))
      throw std::runtime_error("benchmark JSON: a run without a name or cpu_time");
    const double ns = cpu * nanosecondsPer(b.value("time_unit", std::string("ns")));
    const bool chai3d_tick = name.rfind("BM_Chai3dTick/", 0) == 0;  // its own table
    if (!chai3d_tick && (number(b, "allocs_per_tick", allocs) || number(b, "allocs_per_step", allocs))) {
      ticks << "| `" << markdownCell(name) << "` | " << timeText(ns) << " | " << counterText(allocs) << " | "
            << (ns > 0.0 ? wholeText(1e6 / ns) : std::string("-")) << " |\n";
      ++tick_rows;
    }
    if (!number(b, "error", error)) continue;
    // Family / swept argument / other arguments (the curve), as tools/plots/bench_summary.py does.
    std::vector<std::string> parts;
    std::stringstream split(name);
    for (std::string part; std::getline(split, part, '/');) parts.push_back(part);
    std::string curve;
    for (std::size_t k = 2; k < parts.size(); ++k) curve += (curve.empty() ? "" : " ") + parts[k];
    const std::string label = b.value("label", std::string());
    if (!label.empty()) curve += (curve.empty() ? "" : " ") + label;
    std::string swept, value;
    if (parts.size() > 1) {
      const auto colon = parts[1].find(':');
      swept = colon == std::string::npos ? "" : parts[1].substr(0, colon);
      value = colon == std::string::npos ? parts[1] : parts[1].substr(colon + 1);
    }
    auto it = std::find_if(curves.begin(), curves.end(),
                           [&](const Curve& c) { return c.family == parts[0] && c.curve == curve; });
    if (it == curves.end()) it = curves.insert(curves.end(), Curve{parts[0], curve, swept, {}});
    const bool bold = number(b, "default", is_default) && is_default != 0.0;
    const std::string text = (value.empty() ? "" : value + ": ") + timeText(ns) + " " + errorText(error);
    it->points.push_back(bold ? "**" + text + "**" : text);
  }
  GeneratedRegions out;
  if (tick_rows > 0) out["bench-ticks"] = ticks.str();
  const std::string chai3d_tick = chai3dTickTable(data, head.str());
  if (!chai3d_tick.empty()) out["bench-chai3d-tick"] = chai3d_tick;
  if (!curves.empty()) {
    std::ostringstream tve;
    tve << head.str() << "| benchmark | curve | swept | time per call and error at each value (default in bold) |\n"
        << "|---|---|---|---|\n";
    for (const auto& c : curves) {
      tve << "| `" << markdownCell(c.family) << "` | " << markdownCell(c.curve) << " | " << markdownCell(c.swept) << " | ";
      for (std::size_t k = 0; k < c.points.size(); ++k) tve << (k ? "; " : "") << markdownCell(c.points[k]);
      tve << " |\n";
    }
    out["bench-time-vs-error"] = tve.str();
  }
  return out;
}

std::vector<std::string> generatedRegionNames(const std::string& markdown) {
  std::vector<std::string> names;
  for (const auto& r : findRegions(markdown, "markdown")) names.push_back(r.name);
  return names;
}

std::string rewriteGeneratedRegions(const std::string& markdown, const GeneratedRegions& regions,
                                    const std::string& name) {
  const std::vector<Region> found = findRegions(markdown, name);
  if (found.empty())
    throw std::runtime_error(name + " has no generated region: mark each generated table with a line "
                             "'<!-- begin generated: NAME -->' before it and '<!-- end generated: NAME -->' "
                             "after it (NAME: one of " + regionList(regions) + ")");
  for (const auto& r : found)
    if (regions.find(r.name) == regions.end())
      throw std::runtime_error(name + ": region '" + r.name + "' cannot be generated from this run (it can make: " +
                               regionList(regions) + "); reproduction-* regions come from --out's */reproduction.csv, "
                               "bench-* regions from --bench-json");
  std::string out;
  std::size_t copied = 0;
  for (const auto& r : found) {
    out.append(markdown, copied, r.content_begin - copied);
    const std::string& content = regions.at(r.name);
    out += "\n" + content + (content.empty() || content.back() == '\n' ? "" : "\n") + "\n";
    copied = r.content_end;
  }
  out.append(markdown, copied, std::string::npos);
  return out;
}

}  // namespace uhaptics::experiments
