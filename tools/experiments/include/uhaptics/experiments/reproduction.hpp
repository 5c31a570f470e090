#pragma once
// A reproduction table: each published number next to the measured one, with the tolerance that
// decides pass/fail. Every experiment tool writes one (reproduction.csv in its output folder) and
// prints it; the report collects them all.
#include <string>
#include <vector>

namespace uhaptics::experiments {

struct ReproductionRow {
  std::string paper;      // "000", "001", "003"
  std::string quantity;   // e.g. "K at home"
  double published;       // the paper's number (NaN when the paper gives only a bound or a shape)
  double measured;
  std::string criterion;  // how pass is decided, human-readable, e.g. "|m - p| <= 0.5" or "< 1 mm"
  bool pass;
  std::string unit;
  /// Non-empty when the row cannot be decided without data the paper does not publish: why. Such a
  /// row is shown with its reason and, when it misses, counts as "needs data", not as a failure.
  std::string needs_data = {};
  /// Whether the row makes a run fail: it missed and it is decidable from what is published.
  bool fails() const noexcept { return !pass && needs_data.empty(); }
};

/// "pass", "FAIL" or "needs data".
std::string resultWord(const ReproductionRow& row);

class ReproductionTable {
 public:
  void add(ReproductionRow row) { rows_.push_back(std::move(row)); }
  /// Convenience: pass when |measured - published| <= abs_tol.
  void addWithin(const std::string& paper, const std::string& quantity, double published, double measured,
                 double abs_tol, const std::string& unit);
  /// Convenience: a bound (published is NaN); pass decided by the caller.
  void addBound(const std::string& paper, const std::string& quantity, double measured,
                const std::string& criterion, bool pass, const std::string& unit);
  const std::vector<ReproductionRow>& rows() const noexcept { return rows_; }
  /// No row fails (rows that need unpublished data do not count).
  bool allPass() const noexcept;
  /// Marks the last row added as needing data the paper does not publish (see ReproductionRow).
  void markNeedsData(const std::string& reason);
  /// Columns: paper,quantity,published,measured,criterion,pass,unit,needs_data; the result column
  /// reads pass, FAIL, or "needs data" for a missed row that needs unpublished data.
  void writeCsv(const std::string& path) const;
  /// Reads what writeCsv wrote (throws std::runtime_error on a malformed file).
  static ReproductionTable readCsv(const std::string& path);
  /// Aligned text table for the terminal.
  std::string format() const;

 private:
  std::vector<ReproductionRow> rows_;
};

}  // namespace uhaptics::experiments
