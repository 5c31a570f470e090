#pragma once
// The TAU's spring-wall baseline (paper 001): F = k x (+ damping) along the surface normal through
// J^T. A servo-rate class with preallocated state; tick() never allocates or throws, and a bad
// input yields a Fault with a zero torque command.
#include "uhaptics/core/types.hpp"
#include "uhaptics/models/tau_model.hpp"
#include "uhaptics/renderers/tau_wall_front_end.hpp"

namespace uhaptics {

class SpringWallRenderer {
 public:
  struct Options {
    double stiffness = 6000.0;  // N/m, paper 001's baseline
    double damping = 0.0;       // rendered damping B_r (paper: 0, device damping 4 Ns/m instead)
    bool gravity_compensation = true;
  };
  SpringWallRenderer(const TauModel& model, const Options& options);
  explicit SpringWallRenderer(const TauModel& model) : SpringWallRenderer(model, Options{}) {}
  void reset() noexcept;
  const WallCommand& tick(const Vec6& q, const SurfaceContact& contact, const Vec6* pose = nullptr) noexcept;
  const WallCommand& command() const noexcept { return cmd_; }

 private:
  TauServoFrontEnd front_;
  Options options_;
  WallCommand cmd_;
};

}  // namespace uhaptics
