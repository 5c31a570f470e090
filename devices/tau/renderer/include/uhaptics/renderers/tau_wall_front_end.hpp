#pragma once
// What the TAU's wall renderers (LqrWallRenderer, SpringWallRenderer) share: the contact they
// render, the command they return, and their per-tick input stage.
//
// The environment (CHAI3D's proxy algorithm, or the study's flat wall) describes the constraint as
// a SurfaceContact: a point on the surface and its outward unit normal (locally a plane), so any
// surface the environment constrains can be rendered, not only z = 0.
#include "uhaptics/core/fault.hpp"
#include "uhaptics/core/types.hpp"
#include "uhaptics/models/tau_model.hpp"

namespace uhaptics {

struct SurfaceContact {
  bool active = false;            // the environment reports the tool at or inside the surface
  Vec3 point = Vec3::Zero();      // a point of the surface near the tool (the proxy)
  Vec3 normal = Vec3::UnitZ();    // outward unit normal there
};

struct WallCommand {
  Vec6 torque = Vec6::Zero();     // joint torques, finite and within the device limits
  Fault fault = Fault::kNone;
  bool in_contact = false;
  bool saturated = false;
  double penetration = 0.0;       // depth below the surface (m), 0 outside
};

/// Shared per-tick front end: validated inputs, forward kinematics (or a caller-supplied pose),
/// velocity by backward difference of the encoder readings, gravity compensation. A reading equal
/// to the previous one (quantized encoders at rest, most ticks of a held contact) with the same
/// pose reuses the kinematics and gravity: forward() would return them unchanged.
class TauServoFrontEnd {
 public:
  explicit TauServoFrontEnd(const TauModel& model);
  void reset() noexcept;
  /// Per servo period, encoder reading q [rad]: kNone, or the fault that forces a zero command
  /// (kNonFiniteInput also for an active contact whose normal is not a unit vector).
  Fault update(const Vec6& q, const SurfaceContact& contact, const Vec6* pose) noexcept;
  /// The same from forward kinematics the caller already solved for q (TauModel::forward(q, solved)
  /// returned kNone): its pose and Jacobian are taken as they are, the model is not evaluated again.
  Fault update(const Vec6& q, const SurfaceContact& contact, const TauData& solved) noexcept;
  const TauModel& model() const noexcept { return model_; }
  TauData& data() noexcept { return data_; }
  const Vec6& q() const noexcept { return q_; }
  const Vec6& qd() const noexcept { return qd_; }
  const Vec6& pose() const noexcept { return data_.pose; }
  /// Signed distance of the tool centre point above the contact plane (m).
  double signedDistance(const SurfaceContact& c) const noexcept { return c.normal.dot(data_.pose.head<3>() - c.point); }

 private:
  // The checks and the velocity estimate both update() share; false: kNonFiniteInput.
  /// Checks the inputs and takes q as the new reading; same_q: q equals the previous reading.
  bool acceptInputs(const Vec6& q, const SurfaceContact& contact, bool& same_q) noexcept;
  const TauModel& model_;
  TauData data_;
  Vec6 q_ = Vec6::Zero(), qd_ = Vec6::Zero();
  bool has_previous_ = false;
  bool data_current_ = false;  // data_ holds the kinematics and gravity at q_
};

}  // namespace uhaptics
