#pragma once
// What the joint-space (zwidth.cpp) and task-space (task_zwidth.cpp) Z-width harnesses share: the
// scripted user's smooth ramps and the servo clock's tick counts.
#include <cmath>

namespace uhaptics::experiments::zwidth_detail {

inline constexpr double kPi = 3.14159265358979323846;

/// 0 before x = 0, 1 after x = 1, a raised cosine between.
inline double raisedCosine(double x) noexcept {
  return x <= 0.0 ? 0.0 : x >= 1.0 ? 1.0 : 0.5 * (1.0 - std::cos(kPi * x));
}

inline long ticksFor(double seconds, double period) noexcept { return std::lround(seconds / period); }

}  // namespace uhaptics::experiments::zwidth_detail
