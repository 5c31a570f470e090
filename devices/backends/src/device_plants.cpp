#include "uhaptics/backends/device_plants.hpp"

#include <cmath>

#include "uhaptics/core/fault.hpp"

namespace uhaptics {

FixedStepClock::FixedStepClock(double period, double max_catch_up) : period_(period) {
  if (!(period > 0.0) || !std::isfinite(period) || !(max_catch_up >= period) || !std::isfinite(max_catch_up))
    throw Error("FixedStepClock: the period must be finite and > 0, the catch-up limit at least one period");
  max_steps_ = static_cast<long>(std::floor(max_catch_up / period));
}

long FixedStepClock::take(double dt) noexcept {
  if (!(dt > 0.0) || !std::isfinite(dt)) return 0;
  pending_ += dt;
  // A billionth of a period of slack: a caller whose dt is the period computed another way (1 / rate)
  // gets one step per call, not 0 and then 2.
  const double steps = std::floor(pending_ / period_ + 1e-9);
  pending_ -= steps * period_;
  if (steps > static_cast<double>(max_steps_)) {
    dropped_ += (steps - static_cast<double>(max_steps_)) * period_;
    return max_steps_;
  }
  return static_cast<long>(steps);
}

}  // namespace uhaptics
