#pragma once
// The RHI's simulation as its board drives it: 4 joint angles [rad], 4 joint torques [N m]
// (SimulatedPlanarLinkage<4>). Its user: a grip holding the end effector at home (the paper 003
// palpation set-up).
#include <memory>

#include "uhaptics/backends/device_plants.hpp"
#include "uhaptics/backends/simulated_planar_linkage.hpp"
#include "uhaptics/models/planar_linkage_model.hpp"

namespace uhaptics {

class RhiBoardPlant final : public HeldTorquePlant<4> {
 public:
  struct Options {
    double substep = 1e-4;            // integration step [s]
    double hand_stiffness = 800.0;    // grip holding the end effector at home [N/m]
    double hand_damping = 8.0;        // [N s/m]
  };
  RhiBoardPlant(Rhi4Model model, const Options& options);
  void advance(double dt) noexcept override;

  const SimulatedPlanarLinkage<4>& sim() const noexcept { return sim_; }

 private:
  const Vec<4>& sensed() const noexcept override { return sim_.position(); }
  SimulatedPlanarLinkage<4> sim_;
  FixedStepClock clock_;
};

}  // namespace uhaptics
