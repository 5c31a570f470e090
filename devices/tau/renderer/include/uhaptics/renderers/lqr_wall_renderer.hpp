#pragma once
// The TAU's LQR position-control wall (paper 001): the tool held on the environment's surface by
// LqrJointRegulator. A servo-rate class with preallocated state; tick() never allocates or throws,
// and a bad input yields a Fault with a zero torque command.
#include <Eigen/LU>

#include "uhaptics/core/fault.hpp"
#include "uhaptics/core/types.hpp"
#include "uhaptics/models/tau_model.hpp"
#include "uhaptics/renderers/lqr_joint_regulator.hpp"
#include "uhaptics/renderers/tau_wall_front_end.hpp"

namespace uhaptics {

class LqrWallRenderer {
 public:
  struct Options {
    // Release when the tool is this far above the surface [m], >= 0: about two encoder counts at
    // the tool, so quantization alone never releases a held contact.
    double release_distance = 2e-4;
    bool gravity_compensation = true;
    // true: the reference follows the tool along the surface (the tool slides, only the normal
    // motion is held); false: paper 001's fixed reference, the whole pose is held at the entry point.
    bool follow_tangentially = true;
    // true: push only (release when the tool leaves the surface and the controller would pull);
    // false: paper 001's position hold, bilateral while in contact (used by the study).
    bool unilateral = true;
    // false: per-joint saturation (what the motors do; the unsaturated joints keep holding at full
    // gain, so the contact force bends away from the normal). true: the contact torque is scaled
    // down as a whole until gravity compensation plus it fit the torque limits, so the wall pushes
    // less hard but still along its normal (for a tool the user moves freely along the surface,
    // where a bent force pushes it sideways; docs/tau.md, "Velocity observer and sliding").
    bool keep_direction = false;
  };
  /// Keeps a reference to model (it must outlive the renderer); gains from designLqrWall. Throws
  /// uhaptics::Error on a negative release_distance or non-finite gains.
  LqrWallRenderer(const TauModel& model, const LqrWallGains& gains, const Options& options);
  LqrWallRenderer(const TauModel& model, const LqrWallGains& gains) : LqrWallRenderer(model, gains, Options{}) {}
  void reset() noexcept;
  /// Swap in gains designed at a new operating point (e.g. each new contact), keeping the state.
  void setGains(const LqrWallGains& gains) noexcept { regulator_.setGains(gains); }
  /// One servo period: encoder reading q [rad], the environment's contact (model frame, [m]).
  /// pose: the caller's forward-kinematics result for q (nullptr: computed here).
  /// applied: the torque [N m] the device reports it applied over the last period (nullptr: unknown;
  /// the observer then infers it from the delay model, see LqrJointRegulator::observe).
  /// Returns the command (torque [N m], finite and within the limits; zero with a fault on bad input).
  const WallCommand& tick(const Vec6& q, const SurfaceContact& contact, const Vec6* pose = nullptr,
                          const Vec6* applied = nullptr) noexcept;
  /// The same tick from forward kinematics the caller already solved for q (TauModel::forward(q,
  /// solved) returned kNone; pose and Jacobian are used as they are, e.g. a device's sensed state).
  const WallCommand& tick(const Vec6& q, const SurfaceContact& contact, const TauData& solved,
                          const Vec6* applied = nullptr) noexcept;
  const WallCommand& command() const noexcept { return cmd_; }
  const Vec6& reference() const noexcept { return reference_; }
  const Vec6& integralState() const noexcept { return regulator_.integral(); }
  const LqrJointRegulator& regulator() const noexcept { return regulator_; }

 private:
  const WallCommand& fail(Fault f) noexcept;
  // tick() after the front end's update returned f.
  const WallCommand& tickFrom(Fault f, const Vec6& q, const SurfaceContact& contact, const Vec6* applied) noexcept;
  TauServoFrontEnd front_;
  LqrJointRegulator regulator_;
  Options options_;
  WallCommand cmd_;
  bool observer_started_ = false;
  Vec6 reference_ = Vec6::Zero();  // r = IK(contact pose)
  Vec6 ref_pose_ = Vec6::Zero();
  Vec3 entry_orientation_ = Vec3::Zero();
  Vec<12> error_ = Vec<12>::Zero();
  Eigen::PartialPivLU<Mat6> j_lu_;
};

}  // namespace uhaptics
