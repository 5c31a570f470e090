#pragma once
// Actuator saturation observer (paper 003, eq. 14): a "tank" of unused torque capacity,
//
//   V = (1 - exp(-S prod_i g_i / 4^n)) / (1 - exp(-S / 4^n)),
//   g_i = -4 (tau_i - T_max,i)(tau_i - T_min,i) / (T_max,i - T_min,i)^2  in [0, 1],
//
// V = 1 with every torque at the centre of its range and V = 0 as soon as one actuator reaches a
// limit. This is eq. 14 with the sign (-1)^n moved into each factor; clamping each g_i at zero keeps
// V = 0 outside the box (in eq. 14 as printed, two saturated joints would flip the sign back).
// S shapes the curve: small S makes V ~ prod g_i, large S keeps V near 1 until close to a limit.
#include <algorithm>
#include <cmath>

#include "uhaptics/core/types.hpp"

namespace uhaptics {

/// V in [0, 1]. Non-finite input or an empty range (T_max <= T_min) yields 0 (treated as saturated).
template <int N>
double saturationObserver(const Vec<N>& tau, const Vec<N>& t_min, const Vec<N>& t_max, double shape) noexcept {
  double product = 1.0;
  for (int i = 0; i < N; ++i) {
    const double range = t_max(i) - t_min(i);
    if (!(range > 0.0) || !std::isfinite(tau(i))) return 0.0;
    const double g = -4.0 * (tau(i) - t_max(i)) * (tau(i) - t_min(i)) / (range * range);
    product *= std::clamp(g, 0.0, 1.0);
  }
  if (!(shape > 0.0) || !std::isfinite(shape)) return 0.0;
  const double scale = shape / std::pow(4.0, N);
  const double v = -std::expm1(-scale * product) / -std::expm1(-scale);
  return std::clamp(v, 0.0, 1.0);
}

/// Symmetric limits |tau_i| <= T_i.
template <int N>
double saturationObserver(const Vec<N>& tau, const Vec<N>& limits, double shape) noexcept {
  return saturationObserver<N>(tau, -limits, limits, shape);
}

}  // namespace uhaptics
