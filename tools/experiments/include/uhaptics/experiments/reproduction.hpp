#pragma once
// A reproduction table: each published number next to the measured one, with the tolerance that
// decides pass/fail. Every experiment tool writes one (reproduction.csv in its output folder) and
// prints it; the report collects them all.
#include <algorithm>
#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace uhaptics::experiments {

/// The measured values a row accepts: an interval, each end open or closed, possibly infinite; an
/// open interval with equal ends accepts nothing. Written into reproduction.csv ("[1, 2]",
/// "(-inf, 0.05)"), so that uhaptics-report decides each row again from its numbers.
struct Accepted {
  static constexpr double kInf = std::numeric_limits<double>::infinity();
  double min = -kInf, max = kInf;
  bool min_open = true, max_open = true;

  static Accepted within(double centre, double tolerance) { return {centre - tolerance, centre + tolerance, false, false}; }
  static Accepted below(double bound) { return {-kInf, bound, true, true}; }
  static Accepted atMost(double bound) { return {-kInf, bound, true, false}; }
  static Accepted above(double bound) { return {bound, kInf, true, true}; }
  static Accepted atLeast(double bound) { return {bound, kInf, false, true}; }
  static Accepted openInterval(double a, double b) { return {std::min(a, b), std::max(a, b), true, true}; }
  static Accepted nothing() { return {0.0, 0.0, true, true}; }

  /// False for NaN.
  bool contains(double v) const noexcept;
  /// "[min, max]" with "(" / ")" for open ends, exact (17 significant digits).
  std::string text() const;
  /// Reads text(); throws std::invalid_argument saying what is wrong.
  static Accepted parse(const std::string& text);
};

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
  /// The interval that decides `pass` from `measured`, when the criterion is one (add() then sets
  /// pass from it). Rows without one (a verdict joining several numbers) keep the pass they are given.
  std::optional<Accepted> accepts = {};
  /// Whether the row makes a run fail: it missed and it is decidable from what is published.
  bool fails() const noexcept { return !pass && needs_data.empty(); }
};

/// The paper column of rows that check a device's physical stability (uhaptics-zwidth: the Z-width
/// against Colgate and Brown's bound, the passivity layer's gain) rather than a paper's number.
inline constexpr const char* kStabilityRows = "stability";

/// "pass", "FAIL" or "needs data".
std::string resultWord(const ReproductionRow& row);

class ReproductionTable {
 public:
  /// Adds the row; one with `accepts` gets pass = accepts->contains(measured).
  void add(ReproductionRow row);
  /// Convenience: pass when |measured - published| <= abs_tol.
  void addWithin(const std::string& paper, const std::string& quantity, double published, double measured,
                 double abs_tol, const std::string& unit);
  /// Convenience: a bound (published is NaN); pass decided by the caller.
  void addBound(const std::string& paper, const std::string& quantity, double measured,
                const std::string& criterion, bool pass, const std::string& unit);
  /// A bound (published is NaN) decided by `accepts`.
  void addBound(const std::string& paper, const std::string& quantity, double measured,
                const std::string& criterion, const Accepted& accepts, const std::string& unit);
  const std::vector<ReproductionRow>& rows() const noexcept { return rows_; }
  /// No row fails (rows that need unpublished data do not count).
  bool allPass() const noexcept;
  /// Marks the last row added as needing data the paper does not publish (see ReproductionRow).
  void markNeedsData(const std::string& reason);
  /// Columns: paper,quantity,published,measured,criterion,pass,unit,needs_data,accepts; the result
  /// column reads pass, FAIL, or "needs data" for a missed row that needs unpublished data; accepts
  /// is Accepted::text() or empty.
  void writeCsv(const std::string& path) const;
  /// Reads what writeCsv wrote (or the same without the accepts column), deciding every row that
  /// has an accepted interval again from its measured value. Throws std::runtime_error naming the
  /// file and the row on anything else: not a file, empty, a foreign header, no rows, a row with
  /// the wrong cell count, a number that is not one, an unknown result word, a broken interval, or a
  /// result column that contradicts the row's own interval.
  static ReproductionTable readCsv(const std::string& path);
  /// Rows decided from their numbers (with an accepted interval).
  std::size_t recheckableRows() const noexcept;
  /// Aligned text table for the terminal.
  std::string format() const;

 private:
  std::vector<ReproductionRow> rows_;
};

}  // namespace uhaptics::experiments
