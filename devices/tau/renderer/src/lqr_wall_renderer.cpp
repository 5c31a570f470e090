#include "uhaptics/renderers/lqr_wall_renderer.hpp"

#include <algorithm>
#include <cmath>

#include "uhaptics/core/limits.hpp"
#include "uhaptics/core/lu_condition.hpp"

namespace uhaptics {

LqrWallRenderer::LqrWallRenderer(const TauModel& model, const LqrWallGains& gains, const Options& options)
    : front_(model), regulator_(gains), options_(options) {
  if (!(options.release_distance >= 0.0)) throw Error("LqrWallRenderer: release_distance must be >= 0");
  if (!gains.Kc.allFinite() || !gains.Ki.allFinite()) throw Error("LqrWallRenderer: gains are not finite");
}

void LqrWallRenderer::reset() noexcept {
  front_.reset();
  cmd_ = WallCommand{};
  observer_started_ = false;
}

const WallCommand& LqrWallRenderer::fail(Fault f) noexcept {
  cmd_.torque.setZero();
  cmd_.fault = f;
  cmd_.in_contact = false;
  cmd_.saturated = false;
  cmd_.penetration = 0.0;
  regulator_.clearIntegral();
  regulator_.applied(cmd_.torque);
  return cmd_;
}

const WallCommand& LqrWallRenderer::tick(const Vec6& q, const SurfaceContact& contact, const Vec6* pose,
                                         const Vec6* applied) noexcept {
  return tickFrom(front_.update(q, contact, pose), q, contact, applied);
}

const WallCommand& LqrWallRenderer::tick(const Vec6& q, const SurfaceContact& contact, const TauData& solved,
                                         const Vec6* applied) noexcept {
  return tickFrom(front_.update(q, contact, solved), q, contact, applied);
}

const WallCommand& LqrWallRenderer::tickFrom(Fault f, const Vec6& q, const SurfaceContact& contact,
                                             const Vec6* applied) noexcept {
  if (f != Fault::kNone) return fail(f);
  const TauData& data = front_.data();
  // The observer runs in free space too, so the velocity estimate is settled at contact entry.
  // On the first tick the observer starts at rest, as if held (the torque reported for the period
  // before it, often zero at power-up, did not act on the state it starts from).
  const bool first = !observer_started_;
  if (first) {
    regulator_.reset(q);
    observer_started_ = true;
  }
  regulator_.observe(q, first ? nullptr : applied);
  cmd_.fault = Fault::kNone;
  cmd_.saturated = false;
  if (options_.gravity_compensation) cmd_.torque = data.gravity;
  else cmd_.torque.setZero();

  const double distance = contact.active ? front_.signedDistance(contact) : 0.0;
  const bool was_in_contact = cmd_.in_contact;
  if (!contact.active || distance > options_.release_distance) cmd_.in_contact = false;
  else if (!was_in_contact && distance <= 0.0) cmd_.in_contact = true;
  cmd_.penetration = cmd_.in_contact ? std::max(0.0, -distance) : 0.0;
  if (!cmd_.in_contact) {  // free space: no IK, no LQR
    regulator_.clearIntegral();
    scaleIntoBox(cmd_.torque, front_.model().effortLimits());
    regulator_.applied(cmd_.torque);
    return cmd_;
  }

  // Reference: the tool's own pose moved onto the surface along the normal. It follows the tool
  // tangentially (the tool slides) and keeps its orientation, so only the normal motion is held.
  const Vec3& n = contact.normal;
  if (!was_in_contact) entry_orientation_ = data.pose.tail<3>();
  if (options_.follow_tangentially || !was_in_contact) {
    // Reference: the tool position moved onto the surface along the normal (it follows the tool
    // tangentially, so the tool slides), with the orientation held from the contact entry.
    ref_pose_.head<3>() = data.pose.head<3>() - distance * n;
    ref_pose_.tail<3>() = entry_orientation_;
    const Fault ik = front_.model().inverse(ref_pose_, reference_);
    if (ik != Fault::kNone) return fail(ik);
  }
  j_lu_.compute(data.J);
  if (!rcondAbove(j_lu_, 1e-9)) return fail(Fault::kSingular);
  error_.head<6>() = regulator_.velocity();
  if (options_.follow_tangentially) {
    // No velocity error along the surface either: remove the tangential tool velocity.
    const Vec6 xdot = data.J * regulator_.velocity();
    Vec6 tangential = Vec6::Zero();
    tangential.head<3>() = xdot.head<3>() - n.dot(xdot.head<3>()) * n;
    error_.head<6>() -= j_lu_.solve(tangential);
  }
  error_.tail<6>() = front_.q() - reference_;

  // Bumpless entry: x_i such that the contact torque starts at zero.
  if (!was_in_contact) regulator_.startBumpless(error_);
  Vec6 contact_torque = regulator_.control(error_);
  if (options_.follow_tangentially) {
    // A frictionless surface: drop the tangential part of the contact force (the gain couples the
    // joints, so a normal correction would otherwise also push the tool sideways).
    Vec6 wrench = j_lu_.transpose().solve(contact_torque);
    wrench.head<3>() = n.dot(wrench.head<3>()) * n;
    contact_torque.noalias() = data.J.transpose() * wrench;
  }
  if (options_.unilateral) {
    // A wall only pushes: when the contact wrench would pull the tool into the surface while the
    // tool is outside it, the user is leaving: release instead of attracting.
    const Vec6 wrench = j_lu_.transpose().solve(contact_torque);  // J^T F = tau  ->  F = J^-T tau
    if (was_in_contact && distance > 0.0 && n.dot(wrench.head<3>()) < 0.0) {
      cmd_.in_contact = false;
      cmd_.penetration = 0.0;
      regulator_.clearIntegral();
      scaleIntoBox(cmd_.torque, front_.model().effortLimits());
      regulator_.applied(cmd_.torque);
      return cmd_;
    }
  }
  const Vec6& limit = front_.model().effortLimits();
  if (options_.keep_direction) {
    // The largest share s <= 1 of the contact torque with |gravity_i + s contact_i| <= limit_i.
    double share = 1.0;
    for (int i = 0; i < 6; ++i) {
      const double room = contact_torque(i) > 0.0 ? limit(i) - cmd_.torque(i) : limit(i) + cmd_.torque(i);
      if (std::abs(contact_torque(i)) > room) share = std::min(share, std::max(0.0, room) / std::abs(contact_torque(i)));
    }
    cmd_.torque += share * contact_torque;
    cmd_.saturated = share < 1.0;
    clampSymmetric(cmd_.torque, limit);  // gravity compensation alone beyond a limit (not at rest)
  } else {
    cmd_.torque += contact_torque;
    // Per-joint saturation (what the motors do): the unsaturated joints keep holding at full gain.
    cmd_.saturated = clampSymmetric(cmd_.torque, limit) > 0;
  }
  // Anti-windup by conditional integration: the integrator holds while the actuators saturate.
  if (!cmd_.saturated) regulator_.integrate(error_.tail<6>());
  if (zeroIfNonFinite(cmd_.torque) != Fault::kNone) return fail(Fault::kNonFiniteResult);
  regulator_.applied(cmd_.torque);
  return cmd_;
}

}  // namespace uhaptics
