#pragma once
// A scripted user for simulated devices: a spring-damper whose anchor travels a closed path through
// the device's workspace at constant speed, so an unattended run (a CI job, a headless example)
// moves the device through the scene and touches it. The path is given in units of the workspace
// radius around the workspace centre, so one path suits every device. Instead of the path it can
// follow a recorded session's hand (hand_recording.hpp): the recorded anchor, grip and force limit.
#include <memory>
#include <vector>

#include "uhaptics/backends/hand_recording.hpp"
#include "uhaptics/core/types.hpp"

namespace uhaptics {

struct ScriptedHandOptions {
  /// Closed polyline (last point joins the first), in workspace radii, device frame. At least two
  /// distinct points. Default: straight down from above the centre to below it and back.
  std::vector<Vec3> waypoints{Vec3(0.0, 0.0, 0.5), Vec3(0.0, 0.0, -0.3)};
  double lap_time = 4.0;     // [s] one trip around the path
  double stiffness = 150.0;  // [N/m] hand spring (a relaxed grip, cf. k_h = 40 N/m in paper 001)
  double damping = 4.0;      // [N s/m]
  double max_force = 8.0;    // [N] what a hand comfortably pushes with; the spring saturates here
  /// When set, the hand follows this recording instead of the fields above: its anchor linearly
  /// interpolated between rows (scaled by the workspace radius of the device it moves), the grip and
  /// force limit of the rows; before the first row it is at the first, after the last it holds the
  /// last anchor still.
  std::shared_ptr<const HandRecording> recording;
};

class ScriptedHand {
 public:
  /// Validates the options (throws uhaptics::Error naming the bad field) and precomputes the path.
  ScriptedHand(const ScriptedHandOptions& options, double workspace_radius, const Vec3& centre);

  /// Anchor position [m] and velocity [m/s] at time t [s] (any t: the path repeats; a recording
  /// holds its ends).
  void anchor(double t, Vec3& position, Vec3& velocity) const noexcept;

  struct Grip {
    double stiffness, damping, max_force;  // [N/m], [N s/m], [N]
  };
  /// The grip at time t [s] (constant unless the hand follows a recording).
  Grip grip(double t) const noexcept;

  /// Force [N] the hand applies to a tool at (position, velocity) at time t; zero for non-finite
  /// input, magnitude at most max_force. Allocation-free.
  Vec3 force(double t, const Vec3& position, const Vec3& velocity) const noexcept;

  const ScriptedHandOptions& options() const noexcept { return options_; }

 private:
  ScriptedHandOptions options_;
  std::vector<Vec3> points_;      // waypoints in metres
  std::vector<double> cumulative_;  // arc length at each waypoint; back() = closed-path length
  double speed_ = 0.0;            // [m/s]
  // A recording's rows, the anchor in metres and metres per second; empty for a waypoint path.
  std::vector<double> times_;
  std::vector<Vec3> recorded_anchor_, recorded_velocity_;
  std::vector<Grip> recorded_grip_;

  // The recording's row at or before t and the weight of the next one (0 at or before the first
  // row, 1 after the last).
  void locate(double t, std::size_t& row, double& weight) const noexcept;
};

}  // namespace uhaptics
