#include "uhaptics/tools/csv.hpp"

#include <filesystem>
#include <iomanip>
#include <limits>
#include <stdexcept>

namespace uhaptics::tools {

CsvWriter::CsvWriter(const std::string& path, const std::vector<std::string>& columns)
    : path_(path), columns_(columns.size()) {
  const auto parent = std::filesystem::path(path).parent_path();
  if (!parent.empty()) std::filesystem::create_directories(parent);
  out_.open(path, std::ios::trunc);
  if (!out_) throw std::runtime_error(path + ": cannot write CSV file");
  out_ << std::setprecision(std::numeric_limits<double>::max_digits10);
  for (std::size_t i = 0; i < columns.size(); ++i) out_ << (i ? "," : "") << columns[i];
  out_ << '\n';
}

void CsvWriter::check(std::size_t n) {
  if (n != columns_)
    throw std::logic_error(path_ + ": row has " + std::to_string(n) + " cells, header has " +
                           std::to_string(columns_));
}

void CsvWriter::row(std::initializer_list<double> values) {
  check(values.size());
  bool first = true;
  for (double v : values) {
    out_ << (first ? "" : ",") << v;
    first = false;
  }
  out_ << '\n';
}

void CsvWriter::row(const std::vector<double>& values) {
  check(values.size());
  for (std::size_t i = 0; i < values.size(); ++i) out_ << (i ? "," : "") << values[i];
  out_ << '\n';
}

void CsvWriter::row(const std::string& label, const std::vector<double>& values) {
  check(values.size() + 1);
  out_ << label;
  for (double v : values) out_ << ',' << v;
  out_ << '\n';
}

}  // namespace uhaptics::tools
