#pragma once
// Minimal CSV output for the experiment tools (not servo code: may allocate).
#include <fstream>
#include <initializer_list>
#include <string>
#include <vector>

namespace uhaptics::tools {

class CsvWriter {
 public:
  /// Creates (truncates) path, creating parent folders, and writes the header. Throws on failure.
  CsvWriter(const std::string& path, const std::vector<std::string>& columns);
  void row(std::initializer_list<double> values);
  void row(const std::vector<double>& values);
  /// A row whose first cell is text (e.g. a method name), then numbers.
  void row(const std::string& label, const std::vector<double>& values);
  const std::string& path() const noexcept { return path_; }

 private:
  void check(std::size_t n);
  std::string path_;
  std::size_t columns_;
  std::ofstream out_;
};

}  // namespace uhaptics::tools
