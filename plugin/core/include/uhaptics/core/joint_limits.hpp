#pragma once
// Joint limits of a device as bounds on linear combinations of its joints, s = C q,
// lower <= s <= upper. C = I gives plain per-joint stops; other rows express the limits of coupled
// mechanisms, e.g. the internal angle q1 - q2 of a parallelogram driven from its base, which
// cannot fold flat whatever q1 and q2 are on their own.
//
// Smooth avoidance: inside an activation margin delta of a bound, with distance d > 0 to it,
//
//   P(d) = (delta - d)^2 / d          (0 for d >= delta)
//   dP/dd = 1 - delta^2 / d^2         (0 at d = delta: P is C1; -> -inf at the bound)
//
// so the avoidance torque -k dP/dq is zero away from the limits, grows continuously as a limit
// comes within delta and without bound at it. A redundant device feeds it into its null-space
// task; offline self-motion searches add k P to their cost. Allocation-free and noexcept.
#include <algorithm>
#include <cmath>
#include <limits>

#include "uhaptics/core/types.hpp"

namespace uhaptics {

template <int N>
struct JointLimits {
  Mat<N, N> map = Mat<N, N>::Identity();  // row j: coefficients of limited coordinate s_j
  Vec<N> lower = Vec<N>::Constant(-std::numeric_limits<double>::infinity());
  Vec<N> upper = Vec<N>::Constant(std::numeric_limits<double>::infinity());

  /// True when some bound is finite.
  bool any() const noexcept {
    for (int j = 0; j < N; ++j)
      if (std::isfinite(lower(j)) || std::isfinite(upper(j))) return true;
    return false;
  }
  /// Finite map, lower < upper for every row (infinite bounds allowed), no NaN.
  bool valid() const noexcept {
    if (!map.allFinite()) return false;
    for (int j = 0; j < N; ++j)
      if (std::isnan(lower(j)) || std::isnan(upper(j)) || !(lower(j) < upper(j))) return false;
    return true;
  }
  /// Distance to the nearest bound, min_j min(s_j - lower_j, upper_j - s_j) (negative when one is
  /// violated, +inf without finite bounds) [rad].
  double distance(const Vec<N>& q) const noexcept {
    const Vec<N> s = map * q;
    double d = std::numeric_limits<double>::infinity();
    for (int j = 0; j < N; ++j) d = std::min({d, s(j) - lower(j), upper(j) - s(j)});
    return d;
  }
  bool contains(const Vec<N>& q, double tolerance = 0.0) const noexcept { return distance(q) >= -tolerance; }
};

namespace detail {
// Distances below this fraction of the margin are treated as at it: keeps P and its slope finite
// when a configuration starts on or beyond a bound (the slope there is already ~ -400).
inline constexpr double kLimitFloor = 0.05;
inline double limitDistance(double d, double margin) noexcept { return std::max(d, kLimitFloor * margin); }
}  // namespace detail

/// Barrier potential sum_j P(d_j) over both bounds of every row (see the header comment).
template <int N>
double jointLimitPotential(const JointLimits<N>& limits, const Vec<N>& q, double margin) noexcept {
  if (!(margin > 0.0)) return 0.0;
  const Vec<N> s = limits.map * q;
  double p = 0.0;
  for (int j = 0; j < N; ++j)
    for (const double raw : {s(j) - limits.lower(j), limits.upper(j) - s(j)}) {
      if (!(raw < margin)) continue;  // also skips infinite bounds
      const double d = detail::limitDistance(raw, margin);
      p += (margin - d) * (margin - d) / d + (raw - d) * (1.0 - margin * margin / (d * d));  // linear below the floor
    }
  return p;
}

/// grad = dP/dq of jointLimitPotential.
template <int N>
void jointLimitGradient(const JointLimits<N>& limits, const Vec<N>& q, double margin, Vec<N>& grad) noexcept {
  grad.setZero();
  if (!(margin > 0.0)) return;
  const Vec<N> s = limits.map * q;
  for (int j = 0; j < N; ++j) {
    const double to_lower = s(j) - limits.lower(j), to_upper = limits.upper(j) - s(j);
    if (to_lower < margin) {
      const double d = detail::limitDistance(to_lower, margin);
      grad += (1.0 - margin * margin / (d * d)) * limits.map.row(j).transpose();  // d(to_lower)/dq = +row
    }
    if (to_upper < margin) {
      const double d = detail::limitDistance(to_upper, margin);
      grad -= (1.0 - margin * margin / (d * d)) * limits.map.row(j).transpose();  // d(to_upper)/dq = -row
    }
  }
}

}  // namespace uhaptics
