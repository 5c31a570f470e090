#include "uhaptics/backends/rhi_plant.hpp"

#include "uhaptics/core/fault.hpp"

namespace uhaptics {

RhiBoardPlant::RhiBoardPlant(Rhi4Model model, const Options& options)
    : sim_(std::move(model), options.substep), clock_(options.substep) {
  if (!(options.hand_stiffness >= 0.0) || !(options.hand_damping >= 0.0))
    throw Error("RhiBoardPlant: hand stiffness and damping must be >= 0");
  EndEffectorLoad hand;
  hand.anchor = sim_.endEffectorPosition();
  hand.stiffness = options.hand_stiffness * Mat2::Identity();
  hand.damping = options.hand_damping * Mat2::Identity();
  sim_.setLoad(hand);
}

void RhiBoardPlant::advance(double dt) noexcept {
  const long n = clock_.take(dt);
  if (n > 0) sim_.step(command_, static_cast<double>(n) * clock_.period());
}

}  // namespace uhaptics
