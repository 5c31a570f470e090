#pragma once
// Versioned JSON parameter files for device models (devices/<folder>/params/*.json).
//
// Every entry is either a bare number or an object that documents it:
//   "proximal_length": {"value": 0.045, "unit": "m", "source": "assumed: index finger, DESIGN.md"}
// Keys are paths below the root separated by '/', e.g. "geometry/proximal_length".
// Every accessor validates and throws uhaptics::Error naming the file, the key, the value and the
// accepted range, so a malformed file never yields a half-initialized model.
//
// The loader's reads are the file's schema, written once: every accessor records the key, its kind
// and range (fields()), and rejectUnreadKeys() refuses a key nobody read, naming it and the nearest
// key the loader knows. docs/parameter-files.md shows each device's schema, generated from these
// records (tests/backends/param_schema_test.cpp).
#include <memory>
#include <string>
#include <vector>

#include "uhaptics/core/fault.hpp"
#include "uhaptics/core/types.hpp"

namespace uhaptics {

/// One field as a loader read it.
struct ParamField {
  enum class Kind { kNumber, kInteger, kNumbers, kText };
  std::string key;
  Kind kind = Kind::kNumber;
  std::size_t count = 1;  // array length for kNumbers
  double lo = 0.0, hi = 0.0;  // accepted range (numbers, integers, each array element)
  bool required = true;   // false: numberOr, the loader has a default
  std::string unit;       // the file's "unit" beside the value, when it has one
};

class ParamFile {
 public:
  /// Members any object may carry beside its values; they document, nobody reads them.
  static const std::vector<std::string>& descriptiveKeys();
  /// The section of a device's file that the board layer reads (devices/protocol, devices/backends);
  /// a model loader leaves it to them.
  static constexpr const char* kBoardSection = "usb";
  /// The section stating what the device renders stably (its rated wall stiffness), which the board
  /// layer reads into BoardSpec; a model loader leaves it too.
  static constexpr const char* kStabilitySection = "stability";

  /// Reads and parses a file; throws Error if it is missing, a folder, unreadable or not valid JSON.
  static ParamFile load(const std::string& path);
  /// Parses text; origin names it in error messages.
  static ParamFile parse(const std::string& text, const std::string& origin);

  const std::string& origin() const noexcept;

  /// Checks the "device" and "format_version" fields against what a model understands.
  void requireFormat(const std::string& device, int supported_version) const;

  bool has(const std::string& key) const;
  /// A finite number within [lo, hi].
  double number(const std::string& key, double lo, double hi) const;
  /// Like number(), with a default when the key is absent (still validated when present).
  double numberOr(const std::string& key, double fallback, double lo, double hi) const;
  /// An integer within [lo, hi].
  long integer(const std::string& key, long lo, long hi) const;
  /// An array of exactly n finite numbers, each within [lo, hi].
  std::vector<double> numbers(const std::string& key, std::size_t n, double lo, double hi) const;
  template <int N>
  Vec<N> vector(const std::string& key, double lo, double hi) const {
    const auto v = numbers(key, static_cast<std::size_t>(N), lo, hi);
    return Eigen::Map<const Vec<N>>(v.data());
  }
  std::string text(const std::string& key) const;

  /// Once a loader is done: throws Error naming every key of the file that no accessor read (with
  /// the nearest key the loaders asked for), except descriptive members and keys under the given
  /// sections, which another layer reads and checks.
  void rejectUnreadKeys(const std::vector<std::string>& sections_read_elsewhere = {}) const;
  /// The fields read so far, in first-read order: the file's schema as its loaders know it.
  std::vector<ParamField> fields() const;

  /// Throws Error("<origin>: <what>") — for cross-field checks done by the models.
  [[noreturn]] void fail(const std::string& what) const;

 private:
  struct Impl;
  explicit ParamFile(std::shared_ptr<Impl> impl);
  std::shared_ptr<Impl> impl_;
};

/// The edit distance (insertions, deletions, substitutions, adjacent transpositions) between a and b:
/// how near a misspelt key is to a known one.
std::size_t editDistance(const std::string& a, const std::string& b);

}  // namespace uhaptics
