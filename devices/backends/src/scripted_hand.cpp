#include "uhaptics/backends/scripted_hand.hpp"

#include <cmath>
#include <string>

#include "uhaptics/core/fault.hpp"

namespace uhaptics {
namespace {

void requirePositive(double value, const char* name) {
  if (!std::isfinite(value) || value <= 0.0) {
    throw Error(std::string("scripted hand: ") + name + " must be finite and > 0, got " +
                std::to_string(value));
  }
}

}  // namespace

ScriptedHand::ScriptedHand(const ScriptedHandOptions& options, double workspace_radius,
                           const Vec3& centre)
    : options_(options) {
  requirePositive(workspace_radius, "workspace radius");
  requirePositive(options.lap_time, "lap_time");
  requirePositive(options.stiffness, "stiffness");
  requirePositive(options.max_force, "max_force");
  if (!std::isfinite(options.damping) || options.damping < 0.0) {
    throw Error("scripted hand: damping must be finite and >= 0, got " + std::to_string(options.damping));
  }
  if (!centre.allFinite()) throw Error("scripted hand: workspace centre is not finite");
  if (options.waypoints.size() < 2) throw Error("scripted hand: the path needs at least two waypoints");
  points_.reserve(options.waypoints.size());
  for (const Vec3& w : options.waypoints) {
    if (!w.allFinite() || w.norm() > 2.0) {
      throw Error("scripted hand: waypoints must be finite and within two workspace radii of the centre");
    }
    points_.push_back(centre + workspace_radius * w);
  }
  cumulative_.reserve(points_.size() + 1);
  cumulative_.push_back(0.0);
  for (std::size_t i = 0; i < points_.size(); ++i) {
    const Vec3& next = points_[(i + 1) % points_.size()];
    cumulative_.push_back(cumulative_.back() + (next - points_[i]).norm());
  }
  if (cumulative_.back() <= 1e-9 * workspace_radius) {
    throw Error("scripted hand: the waypoints are all the same point");
  }
  speed_ = cumulative_.back() / options.lap_time;
}

void ScriptedHand::anchor(double t, Vec3& position, Vec3& velocity) const noexcept {
  const double length = cumulative_.back();
  double s = std::fmod(speed_ * t, length);
  if (!(s >= 0.0)) s = std::isfinite(s) ? s + length : 0.0;  // negative time, or NaN -> start
  // Few waypoints: a linear scan is faster than a binary search and allocation-free either way.
  std::size_t i = 0;
  while (i + 2 < cumulative_.size() && cumulative_[i + 1] <= s) ++i;
  const Vec3& a = points_[i];
  const Vec3& b = points_[(i + 1) % points_.size()];
  const double segment = cumulative_[i + 1] - cumulative_[i];
  if (segment <= 0.0) {  // repeated waypoint: stand still on it
    position = a;
    velocity.setZero();
    return;
  }
  const double u = (s - cumulative_[i]) / segment;
  position = a + u * (b - a);
  velocity = (speed_ / segment) * (b - a);
}

Vec3 ScriptedHand::force(double t, const Vec3& position, const Vec3& velocity) const noexcept {
  if (!position.allFinite() || !velocity.allFinite() || !std::isfinite(t)) return Vec3::Zero();
  Vec3 anchor_position;
  Vec3 anchor_velocity;
  anchor(t, anchor_position, anchor_velocity);
  Vec3 f = options_.stiffness * (anchor_position - position) + options_.damping * (anchor_velocity - velocity);
  const double magnitude = f.norm();
  if (magnitude > options_.max_force) f *= options_.max_force / magnitude;  // keep the direction
  return f;
}

}  // namespace uhaptics
