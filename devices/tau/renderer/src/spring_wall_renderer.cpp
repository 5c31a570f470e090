#include "uhaptics/renderers/spring_wall_renderer.hpp"

#include <algorithm>
#include <cmath>

#include "uhaptics/core/limits.hpp"

namespace uhaptics {

SpringWallRenderer::SpringWallRenderer(const TauModel& model, const Options& options) : front_(model), options_(options) {
  if (!(options.stiffness >= 0.0) || !(options.damping >= 0.0) || !std::isfinite(options.stiffness + options.damping))
    throw Error("SpringWallRenderer: stiffness and damping must be finite and >= 0");
}

void SpringWallRenderer::reset() noexcept {
  front_.reset();
  cmd_ = WallCommand{};
}

const WallCommand& SpringWallRenderer::tick(const Vec6& q, const SurfaceContact& contact, const Vec6* pose) noexcept {
  return tickFrom(front_.update(q, contact, pose), contact);
}

const WallCommand& SpringWallRenderer::tick(const Vec6& q, const SurfaceContact& contact, const TauData& solved) noexcept {
  return tickFrom(front_.update(q, contact, solved), contact);
}

const WallCommand& SpringWallRenderer::tickFrom(Fault f, const SurfaceContact& contact) noexcept {
  if (f != Fault::kNone) {
    cmd_ = WallCommand{};
    cmd_.fault = f;
    return cmd_;
  }
  const TauData& data = front_.data();
  cmd_.fault = Fault::kNone;
  if (options_.gravity_compensation) cmd_.torque = data.gravity;
  else cmd_.torque.setZero();
  const double distance = contact.active ? front_.signedDistance(contact) : 1.0;
  cmd_.in_contact = distance < 0.0;
  cmd_.penetration = cmd_.in_contact ? -distance : 0.0;
  if (cmd_.in_contact) {
    const Vec3& n = contact.normal;
    const double normal_speed = n.dot(data.J.topRows<3>() * front_.qd());
    // Push only: the damper may not pull the tool into the wall.
    const double force = std::max(0.0, options_.stiffness * cmd_.penetration - options_.damping * normal_speed);
    cmd_.torque.noalias() += data.J.topRows<3>().transpose() * (force * n);
  }
  cmd_.saturated = scaleIntoBox(cmd_.torque, front_.model().effortLimits()) < 1.0;
  if (zeroIfNonFinite(cmd_.torque) != Fault::kNone) {
    cmd_ = WallCommand{};
    cmd_.fault = Fault::kNonFiniteResult;
  }
  return cmd_;
}

}  // namespace uhaptics
