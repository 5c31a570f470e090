#include "uhaptics/backends/scripted_hand.hpp"

#include <algorithm>
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
  if (!centre.allFinite()) throw Error("scripted hand: workspace centre is not finite");
  if (options.recording) {
    const std::vector<HandSample>& rows = options.recording->samples;
    if (rows.size() < 2) throw Error("scripted hand: a recording needs at least two rows");
    times_.reserve(rows.size());
    recorded_anchor_.reserve(rows.size());
    recorded_velocity_.reserve(rows.size());
    recorded_grip_.reserve(rows.size());
    for (const HandSample& row : rows) {
      using L = HandGripLimits;
      const bool grip_ok = row.stiffness >= L::kMinStiffness && row.stiffness <= L::kMaxStiffness &&
                           row.damping >= 0.0 && row.damping <= L::kMaxDamping && row.max_force >= L::kMinForce &&
                           row.max_force <= L::kMaxForce;
      if (!std::isfinite(row.time) || (!times_.empty() && !(row.time > times_.back())) || !row.anchor.allFinite() ||
          !row.anchor_velocity.allFinite() || row.anchor.norm() > L::kMaxAnchorRadii * (1.0 + 1e-6) || !grip_ok) {
        throw Error("scripted hand: the recording's row at t = " + std::to_string(row.time) +
                    " is out of order, not finite or outside the grip's ranges");
      }
      times_.push_back(row.time);
      recorded_anchor_.push_back(centre + workspace_radius * row.anchor);
      recorded_velocity_.push_back(workspace_radius * row.anchor_velocity);
      recorded_grip_.push_back(Grip{row.stiffness, row.damping, row.max_force});
    }
    return;
  }
  requirePositive(options.lap_time, "lap_time");
  requirePositive(options.stiffness, "stiffness");
  requirePositive(options.max_force, "max_force");
  if (!std::isfinite(options.damping) || options.damping < 0.0) {
    throw Error("scripted hand: damping must be finite and >= 0, got " + std::to_string(options.damping));
  }
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

void ScriptedHand::locate(double t, std::size_t& row, double& weight) const noexcept {
  if (!(t > times_.front())) {  // before the first row, or NaN
    row = 0;
    weight = 0.0;
    return;
  }
  if (t >= times_.back()) {
    row = times_.size() - 2;
    weight = 1.0;
    return;
  }
  row = static_cast<std::size_t>(std::upper_bound(times_.begin(), times_.end(), t) - times_.begin()) - 1;
  weight = (t - times_[row]) / (times_[row + 1] - times_[row]);
}

ScriptedHand::Grip ScriptedHand::grip(double t) const noexcept {
  if (times_.empty()) return Grip{options_.stiffness, options_.damping, options_.max_force};
  std::size_t i = 0;
  double u = 0.0;
  locate(t, i, u);
  const Grip& a = recorded_grip_[i];
  const Grip& b = recorded_grip_[i + 1];
  return Grip{a.stiffness + u * (b.stiffness - a.stiffness), a.damping + u * (b.damping - a.damping),
              a.max_force + u * (b.max_force - a.max_force)};
}

void ScriptedHand::anchor(double t, Vec3& position, Vec3& velocity) const noexcept {
  if (!times_.empty()) {
    std::size_t i = 0;
    double u = 0.0;
    locate(t, i, u);
    position = recorded_anchor_[i] + u * (recorded_anchor_[i + 1] - recorded_anchor_[i]);
    if (t >= times_.back()) {
      velocity.setZero();  // the recording has ended: the hand holds still
    } else {
      velocity = recorded_velocity_[i] + u * (recorded_velocity_[i + 1] - recorded_velocity_[i]);
    }
    return;
  }
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
  const Grip g = grip(t);
  Vec3 f = g.stiffness * (anchor_position - position) + g.damping * (anchor_velocity - velocity);
  const double magnitude = f.norm();
  if (magnitude > g.max_force) f *= g.max_force / magnitude;  // keep the direction
  return f;
}

}  // namespace uhaptics
