#include "uhaptics/backends/board_plant.hpp"

#include <algorithm>

namespace uhaptics {

LinearTestPlant::LinearTestPlant(const Params& p) noexcept : params_(p) {
  params_.joints = std::clamp(p.joints, 1, wire::kMaxChannels);
  params_.actuators = std::clamp(p.actuators, 1, params_.joints);
}

void LinearTestPlant::readJoints(double* positions) noexcept {
  for (int i = 0; i < params_.joints; ++i)
    positions[i] = i < params_.actuators ? q_[i] : params_.passive_ratio * q_[0];
}

void LinearTestPlant::applyCommand(const double* efforts) noexcept {
  for (int i = 0; i < params_.actuators; ++i) effort_[i] = efforts[i];
}

void LinearTestPlant::advance(double dt) noexcept {
  constexpr double kSubstep = 1e-4;
  while (dt > 0.0) {
    const double h = std::min(dt, kSubstep);
    for (int i = 0; i < params_.actuators; ++i) {
      const double acc = (effort_[i] - params_.damping * qd_[i] - params_.stiffness * q_[i]) / params_.mass;
      qd_[i] += h * acc;
      q_[i] += h * qd_[i];
    }
    dt -= h;
  }
}

}  // namespace uhaptics
