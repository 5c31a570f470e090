#pragma once
// The user's side of a session, recorded so that another session can replay it (record and replay,
// Ruffaldi et al., "Standardized evaluation of haptic rendering systems", 2006): a method and its
// baseline then meet the same user. The file format is docs/recording.md; a ScriptedHand follows a
// recording when ScriptedHandOptions::recording is set.
//
// Positions are in workspace radii around the workspace centre, device frame, so one recording suits
// every device; the radius it was recorded with is stated in the file.
#include <atomic>
#include <cstddef>
#include <iosfwd>
#include <string>
#include <vector>

#include "uhaptics/core/types.hpp"

namespace uhaptics {

/// One row of a recording.
struct HandSample {
  double time = 0.0;            // [s] since the session opened
  Vec3 anchor = Vec3::Zero();   // [workspace radii] where the hand's grip pulls the tool to
  Vec3 anchor_velocity = Vec3::Zero();  // [workspace radii / s]
  double stiffness = 0.0;       // [N/m] grip spring
  double damping = 0.0;         // [N s/m] grip damper
  double max_force = 0.0;       // [N] the grip saturates here
  Vec3 scene_force = Vec3::Zero();     // [N] the force the scene asked for (diagnostic)
  Vec3 scene_position = Vec3::Zero();  // [workspace radii] the tool position it computed it from
};

struct HandRecording {
  static constexpr int kFormatVersion = 1;
  double workspace_radius = 0.0;  // [m] of the device it was recorded with
  std::string device;             // the device and backend it was recorded with (information)
  std::string backend;
  std::size_t dropped_rows = 0;   // rows the recorder had no room for (the recording ends early)
  std::vector<HandSample> samples;  // strictly increasing times

  double duration() const noexcept { return samples.empty() ? 0.0 : samples.back().time; }
};

/// The grip's ranges a recording must keep (those of a configured scripted hand).
struct HandGripLimits {
  static constexpr double kMinStiffness = 1.0, kMaxStiffness = 5000.0;  // [N/m]
  static constexpr double kMaxDamping = 500.0;                          // [N s/m]
  static constexpr double kMinForce = 0.01, kMaxForce = 100.0;          // [N]
  static constexpr double kMaxAnchorRadii = 2.0;  // an anchor within two workspace radii of the centre
  // (as a waypoint path's)
};

/// Parses a recording. Throws uhaptics::Error "<origin>:<line>: <field>: <what is wrong>" for a
/// missing or wrong header, a row with too few or too many fields, a non-number, a non-finite value,
/// a value outside the grip's ranges, or a time not after the previous row's. At least two rows.
HandRecording parseHandRecording(std::istream& in, const std::string& origin);
/// Reads the file at path (throws uhaptics::Error naming it when it cannot be read or parsed).
HandRecording readHandRecording(const std::string& path);
/// The recording as the file format's text.
std::string formatHandRecording(const HandRecording& recording);

/// A bounded, preallocated recording of a running session: one writer (the servo tick: record() is
/// allocation- and exception-free) and any number of readers of the rows written so far (rows() with
/// count(), e.g. a thread that writes the file while the session runs). When full it keeps the first
/// rows and counts the ones it drops.
class HandRecorder {
 public:
  /// period [s] between rows; capacity: rows kept. Throws uhaptics::Error for a period that is not
  /// finite and > 0 or a capacity of zero.
  HandRecorder(double period, std::size_t capacity);

  /// Whether a row is due at session time t [s] (the first call always is).
  bool due(double t) const noexcept;
  /// Appends the row (its time must be due); counts it as dropped when the buffer is full.
  void record(const HandSample& sample) noexcept;
  /// Forgets every row: a new session starts at time 0.
  void clear() noexcept;

  std::size_t count() const noexcept { return count_.load(std::memory_order_acquire); }
  std::size_t dropped() const noexcept { return dropped_.load(std::memory_order_relaxed); }
  std::size_t capacity() const noexcept { return rows_.size(); }
  double period() const noexcept { return period_; }
  /// The first count() rows are complete and never change until clear().
  const HandSample* rows() const noexcept { return rows_.data(); }

 private:
  double period_;
  double next_due_ = 0.0;
  std::vector<HandSample> rows_;
  std::atomic<std::size_t> count_{0};
  std::atomic<std::size_t> dropped_{0};
};

}  // namespace uhaptics
