#include "uhaptics/experiments/reproduction.hpp"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace uhaptics::experiments {

namespace {
std::string number(double v) {
  if (std::isnan(v)) return "-";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

// CSV cell: quoted when it holds a comma or a quote.
std::string cell(const std::string& s) {
  if (s.find_first_of(",\"") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) out += (c == '"') ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

std::vector<std::string> splitCsvLine(const std::string& line) {
  std::vector<std::string> cells(1);
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') { cells.back() += '"'; ++i; }
      else if (c == '"') quoted = false;
      else cells.back() += c;
    } else if (c == '"') quoted = true;
    else if (c == ',') cells.emplace_back();
    else cells.back() += c;
  }
  return cells;
}
}  // namespace

void ReproductionTable::addWithin(const std::string& paper, const std::string& quantity, double published,
                                  double measured, double abs_tol, const std::string& unit) {
  const bool pass = std::isfinite(measured) && std::abs(measured - published) <= abs_tol;
  add({paper, quantity, published, measured, "|measured - published| <= " + number(abs_tol), pass, unit});
}

void ReproductionTable::addBound(const std::string& paper, const std::string& quantity, double measured,
                                 const std::string& criterion, bool pass, const std::string& unit) {
  add({paper, quantity, std::numeric_limits<double>::quiet_NaN(), measured, criterion,
       pass && std::isfinite(measured), unit});
}

void ReproductionTable::markNeedsData(const std::string& reason) {
  if (rows_.empty() || reason.empty()) throw std::logic_error("markNeedsData needs a row and a reason");
  rows_.back().needs_data = reason;
}

bool ReproductionTable::allPass() const noexcept {
  for (const auto& r : rows_)
    if (r.fails()) return false;
  return true;
}

std::string resultWord(const ReproductionRow& row) {
  if (row.pass) return "pass";
  return row.needs_data.empty() ? "FAIL" : "needs data";
}

void ReproductionTable::writeCsv(const std::string& path) const {
  std::ofstream out(path, std::ios::trunc);
  if (!out) throw std::runtime_error(path + ": cannot write");
  out << "paper,quantity,published,measured,criterion,pass,unit,needs_data\n";
  out.precision(10);
  for (const auto& r : rows_)
    out << cell(r.paper) << ',' << cell(r.quantity) << ',' << r.published << ',' << r.measured << ','
        << cell(r.criterion) << ',' << resultWord(r) << ',' << cell(r.unit) << ',' << cell(r.needs_data) << '\n';
}

ReproductionTable ReproductionTable::readCsv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot read");
  std::string line;
  std::getline(in, line);
  ReproductionTable t;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();  // a file written with CRLF line ends
    if (line.empty()) continue;
    const auto c = splitCsvLine(line);
    if (c.size() != 7 && c.size() != 8) throw std::runtime_error(path + ": malformed row: " + line);
    t.add({c[0], c[1], std::stod(c[2]), std::stod(c[3]), c[4], c[5] == "pass", c[6], c.size() == 8 ? c[7] : ""});
  }
  return t;
}

std::string ReproductionTable::format() const {
  std::size_t wq = 8, wc = 9;
  for (const auto& r : rows_) {
    wq = std::max(wq, r.quantity.size());
    wc = std::max(wc, r.criterion.size());
  }
  std::ostringstream os;
  char buf[1024];
  std::snprintf(buf, sizeof buf, "%-5s  %-*s  %12s  %12s  %-8s  %-*s  %s\n", "paper", static_cast<int>(wq),
                "quantity", "published", "measured", "unit", static_cast<int>(wc), "criterion", "result");
  os << buf;
  for (const auto& r : rows_) {
    std::snprintf(buf, sizeof buf, "%-5s  %-*s  %12s  %12s  %-8s  %-*s  %s\n", r.paper.c_str(),
                  static_cast<int>(wq), r.quantity.c_str(), number(r.published).c_str(),
                  number(r.measured).c_str(), r.unit.c_str(), static_cast<int>(wc), r.criterion.c_str(),
                  resultWord(r).c_str());
    os << buf;
  }
  for (const auto& r : rows_)
    if (!r.pass && !r.needs_data.empty()) os << "needs data: " << r.quantity << ": " << r.needs_data << "\n";
  return os.str();
}

}  // namespace uhaptics::experiments
