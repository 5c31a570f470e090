#pragma once
// What the joint-space (zwidth.cpp) and task-space (task_zwidth.cpp) Z-width harnesses share: the
// hardware path's sensing and command delay, the scripted user's smooth ramps, the servo clock's
// tick counts and the search for the boundary.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

#include "uhaptics/backends/board_plant.hpp"
#include "uhaptics/backends/device_definition.hpp"
#include "uhaptics/backends/joint_io.hpp"
#include "uhaptics/experiments/zwidth.hpp"

namespace uhaptics::experiments::zwidth_detail {

inline constexpr double kPi = 3.14159265358979323846;

using Channels = std::array<double, wire::kMaxChannels>;

/// A plant as the hardware path sees and drives it: joints quantized to the spec's resolution, rates
/// from the board's estimator on a sample clock of the servo period; commands held to the effort
/// limits (non-finite: zero) and acting `delay` periods after the reading they were computed from.
class HardwarePath {
 public:
  HardwarePath(const BoardSpec& spec, double period, int delay)
      : spec_(spec), period_(period), delay_(delay), joints_(spec.descriptor.joints) {
    rate_.setResolution(spec.position_resolution.data(), joints_);
    rate_.reset();
  }

  /// The period's reading; false when one is not finite.
  bool read(BoardPlant& plant) noexcept {
    plant.readJoints(raw_.data());
    for (int i = 0; i < joints_; ++i) {
      const double step = spec_.position_resolution[i];
      q_[i] = step > 0.0 ? std::round(raw_[i] / step) * step : raw_[i];
      if (!std::isfinite(q_[i])) return false;
    }
    const auto sample_us = static_cast<std::uint32_t>(std::llround(static_cast<double>(tick_) * period_ * 1e6));
    rate_.update(q_.data(), joints_, sample_us, rates_.data());
    return true;
  }

  /// Holds this period's command to the limits and queues it; returns the one that acts now (zero
  /// until the first has come through the delay). Advances the clock.
  Channels command(Channels efforts) noexcept {
    for (int a = 0; a < spec_.descriptor.actuators; ++a) {
      const double limit = spec_.descriptor.effort_limit[a];
      efforts[a] = std::isfinite(efforts[a]) ? std::clamp(efforts[a], -limit, limit) : 0.0;
    }
    pending_[slot(tick_)] = efforts;
    Channels applied{};
    if (tick_ >= delay_) applied = pending_[slot(tick_ - delay_)];
    ++tick_;
    return applied;
  }

  const Channels& q() const noexcept { return q_; }
  const Channels& rates() const noexcept { return rates_; }
  long tick() const noexcept { return tick_; }
  double period() const noexcept { return period_; }
  int delay() const noexcept { return delay_; }

 private:
  static std::size_t slot(long tick) noexcept { return static_cast<std::size_t>(tick % (kMaxZWidthDelay + 1)); }

  const BoardSpec& spec_;
  double period_;
  int delay_;
  int joints_;
  JointRateEstimator rate_;
  Channels raw_{}, q_{}, rates_{};
  std::array<Channels, kMaxZWidthDelay + 1> pending_{};
  long tick_ = 0;
};

/// 0 before x = 0, 1 after x = 1, a raised cosine between.
inline double raisedCosine(double x) noexcept {
  return x <= 0.0 ? 0.0 : x >= 1.0 ? 1.0 : 0.5 * (1.0 - std::cos(kPi * x));
}

inline long ticksFor(double seconds, double period) noexcept { return std::lround(seconds / period); }

/// A value's peak-to-peak over a window of ticks (0 until it has seen one).
struct PeakToPeak {
  double lo = 0.0, hi = 0.0;
  bool seen = false;
  void add(double x) noexcept {
    lo = seen ? std::min(lo, x) : x;
    hi = seen ? std::max(hi, x) : x;
    seen = true;
  }
  double width() const noexcept { return hi - lo; }
};

/// What searchStiffness found: the largest K passive and the smallest not (NaN when not bracketed).
struct StiffnessBracket {
  double k_max = std::numeric_limits<double>::quiet_NaN();
  double k_fail = std::numeric_limits<double>::quiet_NaN();
  bool below_range = false;  // nothing passive down to the floor the steps reach
  bool above_range = false;  // passive up to the ceiling: k_max is a lower bound
};

/// The boundary of passive(K): from k0, bracket by factors of 4 (at most max_steps each way), then
/// bisect in log K until the bracket is narrower than 1 + precision.
template <class Passive>
StiffnessBracket searchStiffness(Passive&& passive, double k0, int max_steps, double precision) {
  double lo = std::numeric_limits<double>::quiet_NaN(), hi = lo;
  StiffnessBracket out;
  if (passive(k0)) {
    lo = k0;
    for (int s = 0; s < max_steps && std::isnan(hi); ++s) {
      if (passive(4.0 * lo)) lo *= 4.0;
      else hi = 4.0 * lo;
    }
    out.above_range = std::isnan(hi);
  } else {
    hi = k0;
    for (int s = 0; s < max_steps && std::isnan(lo); ++s) {
      if (passive(0.25 * hi)) lo = 0.25 * hi;
      else hi *= 0.25;
    }
    out.below_range = std::isnan(lo);
  }
  if (!std::isnan(lo) && !std::isnan(hi)) {
    while (hi / lo > 1.0 + precision) {
      const double mid = std::sqrt(lo * hi);
      if (passive(mid)) lo = mid;
      else hi = mid;
    }
  }
  out.k_max = lo;
  out.k_fail = hi;
  return out;
}

/// Copies a bracket into a boundary record (Boundary, TaskBoundary: the same four fields).
template <class BoundaryRecord>
void setBracket(BoundaryRecord& out, const StiffnessBracket& found) noexcept {
  out.k_max = found.k_max;
  out.k_fail = found.k_fail;
  out.above_range = found.above_range;
  out.below_range = found.below_range;
}

}  // namespace uhaptics::experiments::zwidth_detail
