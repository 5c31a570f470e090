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
    double damping = 0.0;       // N s/m, rendered damping B_r (paper: 0, device damping 4 Ns/m instead)
    bool gravity_compensation = true;
  };
  /// Keeps a reference to model (it must outlive the renderer). Throws uhaptics::Error unless
  /// stiffness and damping are finite and >= 0.
  SpringWallRenderer(const TauModel& model, const Options& options);
  explicit SpringWallRenderer(const TauModel& model) : SpringWallRenderer(model, Options{}) {}
  void reset() noexcept;
  /// One servo period: encoder reading q [rad], the environment's contact (model frame, [m]).
  /// pose: the caller's forward-kinematics result for q (nullptr: computed here).
  const WallCommand& tick(const Vec6& q, const SurfaceContact& contact, const Vec6* pose = nullptr) noexcept;
  /// The same tick from forward kinematics the caller already solved for q (TauModel::forward(q,
  /// solved) returned kNone; pose and Jacobian are used as they are).
  const WallCommand& tick(const Vec6& q, const SurfaceContact& contact, const TauData& solved) noexcept;
  const WallCommand& command() const noexcept { return cmd_; }

 private:
  // tick() after the front end's update returned f.
  const WallCommand& tickFrom(Fault f, const SurfaceContact& contact) noexcept;
  TauServoFrontEnd front_;
  Options options_;
  WallCommand cmd_;
};

}  // namespace uhaptics
