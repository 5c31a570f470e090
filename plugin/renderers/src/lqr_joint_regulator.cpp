#include "uhaptics/renderers/lqr_joint_regulator.hpp"

namespace uhaptics {

void LqrJointRegulator::reset(const Vec6& q_measured) noexcept {
  observer_.reset(q_measured);
  integral_.setZero();
  for (Vec6& c : commands_) c = gains_.observer.torque;  // at rest, holding gravity
  head_ = 0;
}

Vec6 LqrJointRegulator::inFlightTerm() const noexcept {
  Vec6 term = Vec6::Zero();
  for (int j = 1; j <= gains_.command_delay; ++j)
    term.noalias() += gains_.Kd.middleCols<6>(6 * (j - 1)) * (commanded(j) - gains_.operating_torque);
  return term;
}

void LqrJointRegulator::observe(const Vec6& q_measured, const Vec6* applied) noexcept {
  // The command that drove the plant over the last period: reported by the device, or else the one
  // issued command_delay periods before it (random delay: the expectation, the mean of the commands
  // it may have been).
  // A non-finite report is ignored like a missing one (the tick's own inputs are validated).
  const bool reported = applied && applied->allFinite();
  Vec6 acting = reported ? *applied : commanded(1 + gains_.command_delay);
  if (!reported && gains_.random_command_delay) {
    for (int j = 1; j <= gains_.command_delay; ++j) acting += commanded(j);
    acting /= static_cast<double>(gains_.command_delay + 1);
  }
  observer_.update(q_measured, acting);
}

}  // namespace uhaptics
