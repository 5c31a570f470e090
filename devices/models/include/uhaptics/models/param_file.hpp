#pragma once
// Versioned JSON parameter files for device models (devices/<folder>/params/*.json).
//
// Every entry is either a bare number or an object that documents it:
//   "proximal_length": {"value": 0.045, "unit": "m", "source": "assumed: index finger, DESIGN.md"}
// Keys are paths below the root separated by '/', e.g. "geometry/proximal_length".
// Every accessor validates and throws uhaptics::Error naming the file, the key, the value and the
// accepted range, so a malformed file never yields a half-initialized model.
#include <memory>
#include <string>
#include <vector>

#include "uhaptics/core/fault.hpp"
#include "uhaptics/core/types.hpp"

namespace uhaptics {

class ParamFile {
 public:
  /// Reads and parses a file; throws Error if it is missing or is not valid JSON.
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

  /// Throws Error("<origin>: <what>") — for cross-field checks done by the models.
  [[noreturn]] void fail(const std::string& what) const;

 private:
  struct Impl;
  explicit ParamFile(std::shared_ptr<const Impl> impl);
  std::shared_ptr<const Impl> impl_;
};

}  // namespace uhaptics
