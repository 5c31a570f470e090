#include "uhaptics/experiments/reproduction.hpp"

#include <cmath>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
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

constexpr const char* kHeader = "paper,quantity,published,measured,criterion,pass,unit,needs_data";

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

std::string exact(double v) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

// A whole cell as a number ("nan" and "inf" included); false when it is not one.
bool parseNumber(const std::string& text, double& v) {
  if (text.empty() || std::isspace(static_cast<unsigned char>(text.front()))) return false;
  char* end = nullptr;
  v = std::strtod(text.c_str(), &end);
  return end == text.c_str() + text.size();
}
}  // namespace

bool Accepted::contains(double v) const noexcept {
  if (std::isnan(v)) return false;
  const bool above_min = min_open ? v > min : v >= min;
  const bool below_max = max_open ? v < max : v <= max;
  return above_min && below_max;
}

std::string Accepted::text() const {
  return std::string(min_open ? "(" : "[") + exact(min) + ", " + exact(max) + (max_open ? ")" : "]");
}

Accepted Accepted::parse(const std::string& text) {
  const auto comma = text.find(',');
  if (text.size() < 5 || comma == std::string::npos || (text.front() != '[' && text.front() != '(') ||
      (text.back() != ']' && text.back() != ')'))
    throw std::invalid_argument("'" + text + "' is not an interval like [1, 2] or (-inf, 0.5)");
  std::string lo = text.substr(1, comma - 1), hi = text.substr(comma + 1, text.size() - comma - 2);
  while (!hi.empty() && hi.front() == ' ') hi.erase(hi.begin());
  Accepted a;
  a.min_open = text.front() == '(';
  a.max_open = text.back() == ')';
  if (!parseNumber(lo, a.min) || !parseNumber(hi, a.max) || std::isnan(a.min) || std::isnan(a.max))
    throw std::invalid_argument("'" + text + "': its ends are not numbers");
  if (a.min > a.max) throw std::invalid_argument("'" + text + "': its lower end is above its upper end");
  return a;
}

void ReproductionTable::add(ReproductionRow row) {
  if (row.accepts) row.pass = row.accepts->contains(row.measured);
  rows_.push_back(std::move(row));
}

std::size_t ReproductionTable::recheckableRows() const noexcept {
  std::size_t n = 0;
  for (const auto& r : rows_) n += r.accepts ? 1 : 0;
  return n;
}

void ReproductionTable::addWithin(const std::string& paper, const std::string& quantity, double published,
                                  double measured, double abs_tol, const std::string& unit) {
  add({paper, quantity, published, measured, "|measured - published| <= " + number(abs_tol), false, unit, {},
       Accepted::within(published, abs_tol)});
}

void ReproductionTable::addBound(const std::string& paper, const std::string& quantity, double measured,
                                 const std::string& criterion, const Accepted& accepts, const std::string& unit) {
  add({paper, quantity, std::numeric_limits<double>::quiet_NaN(), measured, criterion, false, unit, {}, accepts});
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
  out << kHeader << ",accepts\n";
  for (const auto& r : rows_)
    out << cell(r.paper) << ',' << cell(r.quantity) << ',' << exact(r.published) << ',' << exact(r.measured) << ','
        << cell(r.criterion) << ',' << resultWord(r) << ',' << cell(r.unit) << ',' << cell(r.needs_data) << ','
        << cell(r.accepts ? r.accepts->text() : "") << '\n';
  if (!out.flush()) throw std::runtime_error(path + ": cannot write");
}

ReproductionTable ReproductionTable::readCsv(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) throw std::runtime_error(path + ": a folder, not a reproduction table");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot read");
  auto strip = [](std::string& line) {
    if (!line.empty() && line.back() == '\r') line.pop_back();  // a file written with CRLF line ends
  };
  std::string line;
  if (!std::getline(in, line)) throw std::runtime_error(path + ": empty file (expected the header " + kHeader + ")");
  strip(line);
  const bool with_accepts = line == std::string(kHeader) + ",accepts";
  if (!with_accepts && line != kHeader)
    throw std::runtime_error(path + ": line 1 is not the header " + kHeader + "[,accepts]");
  const std::size_t cells = with_accepts ? 9 : 8;
  ReproductionTable t;
  std::size_t row = 0;
  while (std::getline(in, line)) {
    strip(line);
    if (line.empty()) continue;
    ++row;
    const auto c = splitCsvLine(line);
    const std::string where = path + ": row " + std::to_string(row) + " (line " + std::to_string(row + 1) + ")";
    if (c.size() != cells)
      throw std::runtime_error(where + ": " + std::to_string(c.size()) + " cells, expected " + std::to_string(cells));
    ReproductionRow r{c[0], c[1], 0.0, 0.0, c[4], false, c[6], c[7]};
    if (!parseNumber(c[2], r.published)) throw std::runtime_error(where + ": published '" + c[2] + "' is not a number");
    if (!parseNumber(c[3], r.measured)) throw std::runtime_error(where + ": measured '" + c[3] + "' is not a number");
    if (c[5] != "pass" && c[5] != "FAIL" && c[5] != "needs data")
      throw std::runtime_error(where + ": result '" + c[5] + "' is not pass, FAIL or needs data");
    r.pass = c[5] == "pass";
    if (with_accepts && !c[8].empty()) {
      try {
        r.accepts = Accepted::parse(c[8]);
      } catch (const std::invalid_argument& e) {
        throw std::runtime_error(where + ": accepts " + e.what());
      }
      // Decided again from the numbers: a result column that disagrees is refused, not trusted.
      if (r.accepts->contains(r.measured) != r.pass)
        throw std::runtime_error(where + " '" + r.quantity + "': the result column says " + c[5] + " but measured " +
                                 c[3] + " is " + (r.pass ? "outside " : "inside ") + c[8]);
    }
    t.add(std::move(r));
  }
  if (row == 0) throw std::runtime_error(path + ": no rows after the header");
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
