#pragma once
// Shared pieces of the numerical stress suite: seeded generators of adversarial values and a tally
// of the cases tried, printed so a run says how much it covered.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <iostream>
#include <limits>
#include <random>
#include <string>

namespace uhaptics::stress {

/// Scale factor for the randomized loops: 1 in the test command, larger by UHAPTICS_STRESS_SCALE
/// (e.g. UHAPTICS_STRESS_SCALE=100 for a long run).
inline int scale() {
  if (const char* s = std::getenv("UHAPTICS_STRESS_SCALE")) {
    const int v = std::atoi(s);
    if (v > 0) return v;
  }
  return 1;
}

/// Values a sensor or an upstream computation can hand over when something is wrong: NaN, +-Inf,
/// huge, tiny, exactly zero, or ordinary values from a range widened well beyond the nominal one.
class AdversarialSource {
 public:
  explicit AdversarialSource(std::uint64_t seed) : rng_(seed) {}

  double uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng_); }

  /// Nominal range [lo, hi] widened by its own width on each side, plus special values 10 % of the time.
  double around(double lo, double hi) {
    const double u = uniform(0.0, 1.0);
    if (u < 0.02) return std::numeric_limits<double>::quiet_NaN();
    if (u < 0.04) return (u < 0.03 ? 1.0 : -1.0) * std::numeric_limits<double>::infinity();
    if (u < 0.06) return (u < 0.05 ? 1.0 : -1.0) * 1e300;
    if (u < 0.08) return (u < 0.07 ? 1.0 : -1.0) * 1e-300;
    if (u < 0.10) return 0.0;
    const double w = hi - lo;
    return uniform(lo - w, hi + w);
  }

  /// A positive magnitude spread log-uniformly over [10^lo_exp, 10^hi_exp].
  double logUniform(double lo_exp, double hi_exp) { return std::pow(10.0, uniform(lo_exp, hi_exp)); }

  std::mt19937_64& engine() { return rng_; }

 private:
  std::mt19937_64 rng_;
};

/// Counts of what a stress loop tried and how the code under test answered.
struct Tally {
  std::string what;
  long cases = 0;
  long faults = 0;     // refused with a Fault (and a zero command)
  long clamped = 0;    // command limited to the device's range
  long violations = 0; // a non-finite or out-of-limit command, or a non-zero command with a fault

  void print() const {
    std::cout << "stress: " << what << ": " << cases << " cases, " << faults << " faults (zero command), "
              << clamped << " clamped, " << violations << " violations\n";
  }
};

}  // namespace uhaptics::stress
