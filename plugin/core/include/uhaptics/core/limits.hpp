#pragma once
// The last line of defence before a command leaves a renderer: finite and within device limits.
#include <Eigen/Core>
#include <algorithm>
#include <cmath>

#include "uhaptics/core/fault.hpp"

namespace uhaptics {

/// Clamps each entry of cmd to [-limit_i, limit_i]. Returns how many entries were clamped.
template <typename DerivedC, typename DerivedL>
int clampSymmetric(Eigen::MatrixBase<DerivedC>& cmd, const Eigen::MatrixBase<DerivedL>& limit) noexcept {
  int clamped = 0;
  for (Eigen::Index i = 0; i < cmd.size(); ++i) {
    const double lim = limit(i);
    if (cmd(i) > lim) { cmd(i) = lim; ++clamped; }
    else if (cmd(i) < -lim) { cmd(i) = -lim; ++clamped; }
  }
  return clamped;
}

/// Uniform scaling that brings cmd inside the box |cmd_i| <= limit_i while keeping its direction
/// (what a force display wants: a weaker force in the right direction, not a bent one).
/// Returns the scale factor applied, in (0, 1].
template <typename DerivedC, typename DerivedL>
double scaleIntoBox(Eigen::MatrixBase<DerivedC>& cmd, const Eigen::MatrixBase<DerivedL>& limit) noexcept {
  double alpha = 1.0;
  for (Eigen::Index i = 0; i < cmd.size(); ++i) {
    const double a = std::abs(cmd(i));
    if (a > limit(i) && a > 0.0) alpha = std::min(alpha, limit(i) / a);
  }
  if (alpha < 1.0) cmd *= alpha;
  return alpha;
}

/// Replaces a non-finite command by zero. Returns Fault::kNonFiniteResult when it had to.
template <typename Derived>
Fault zeroIfNonFinite(Eigen::MatrixBase<Derived>& cmd) noexcept {
  if (cmd.allFinite()) return Fault::kNone;
  cmd.setZero();
  return Fault::kNonFiniteResult;
}

}  // namespace uhaptics
