#pragma once
// The referee: how a session felt, judged from the simulated plant's truth alone.
//
// A rendering method's figures about itself (its engagements, its own penetration estimate) are
// diagnostics. Whether the user got a stiff, quiet, passive contact is measured here, on the truth
// side of a simulated or emulated device: where the user really holds the tool, the force the
// actuators really exert there (after the board's limits and delay, through the plant), the force
// the user really pushes with, and the force the scene asked for. Nothing here ever reaches a
// rendering policy; a board over USB has no referee (nothing knows the truth there).
//
// A contact begins when the scene's force rises above RefereeOptions::contact_force and ends when
// it falls below half of it. Its entry point is the tool's true position in the period before (the
// last one the scene asked nothing at: a scene's force starts at its surface, so the surface lies
// between the two, and the depth is overstated by at most one period's travel, never understated);
// its outward normal is the scene force's direction at the onset. The depth of every contact tick is
// measured from there, whichever renderer held it, while the scene's force stays within
// max_normal_turn of that normal: beyond it the tool has slid round a curve (a tooth's flank), where
// one plane does not describe the surface; those ticks (turned_samples) leave the depth, the holds
// and the chatter alone and still count for the force error and saturation.
// The figures, per session (docs/chai3d.md, "The referee", says the same for users):
//
//   max_true_penetration_mm    deepest (p_entry - p) . n over every contact tick
//   rendered_stiffness_N_per_m the user's push into the surface over the depth, least squares
//                              through the origin over the holds (contact ticks, after the onset
//                              window, moving slower than hold_speed along n, deeper than
//                              min_hold_depth)
//   rate_hardness_N_per_m      Han and Choi's extended rate-hardness (after Lawrence et al. 2000):
//                              the steepest rise of the applied force along n within onset_window
//                              of a contact's start over the approach speed at the start, averaged
//                              over contacts that approach faster than min_onset_speed
//   force_error_rms_N          |applied - asked| over the contact ticks, RMS
//   generated_energy_mJ        the net energy the device gave the user at the user's port:
//                              -sum F_user . dx (the user's force is held over each period, so the
//                              sum is that period's work exactly)
//   chatter_N                  RMS over the holds of the applied force along n high-passed at
//                              chatter_cutoff_hz (second-order Butterworth)
//   saturated_share            share of the contact ticks with an actuator at its effort limit
//
// observe() is allocation-free and noexcept; report() derives the figures from running sums.
#include <cstdint>
#include <limits>
#include <memory>
#include <mutex>

#include "uhaptics/backends/board_plant.hpp"
#include "uhaptics/backends/lockfree.hpp"
#include "uhaptics/core/types.hpp"

namespace uhaptics {

struct RefereeOptions {
  double contact_force = 0.05;     // [N] the scene's force that begins a contact (ends below half)
  double onset_window = 0.02;      // [s] after a contact's start: rate-hardness; no holds yet
  double min_onset_speed = 0.005;  // [m/s] slower approaches give no rate-hardness sample
  double hold_speed = 0.01;        // [m/s] along the normal: slower contact ticks are holds
  double min_hold_depth = 5e-5;    // [m] shallower holds leave the stiffness alone
  double chatter_cutoff_hz = 30.0; // [Hz]
  double max_normal_turn = 0.5236; // [rad] (30 deg) the scene force's turn that ends the entry plane's validity
  /// Throws Error naming the first option out of range (all > 0, finite).
  void validate() const;
};

/// One period of the plant's truth and what the scene asked, in the device model's task frame.
struct RefereeSample {
  double dt = 0.0;                      // [s] the period this sample closes
  PlantTruth truth;
  Vec3 asked_force = Vec3::Zero();      // [N] the scene's request for this period
};

/// The session's figures (docs/chai3d.md, "The referee"). NaN where a figure had nothing to measure.
struct RefereeReport {
  std::uint64_t samples = 0;          // periods observed
  double seconds = 0.0;               // simulated time observed
  std::uint64_t contacts = 0;
  std::uint64_t contact_samples = 0;
  std::uint64_t hold_samples = 0;
  std::uint64_t onset_samples = 0;    // contacts that gave a rate-hardness sample
  std::uint64_t turned_samples = 0;   // contact ticks whose scene force had turned off the entry normal
  double max_true_penetration_mm = 0.0;
  double rendered_stiffness_N_per_m = kNaN;
  double rate_hardness_N_per_m = kNaN;
  double force_error_rms_N = kNaN;
  double generated_energy_mJ = 0.0;
  double chatter_N = kNaN;
  double saturated_share = kNaN;
  double peak_user_force_N = 0.0;     // how hard the user pushed: a person's hand is bounded
  double peak_applied_force_N = 0.0;  // the largest force the actuators exerted at the tool

  static constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
};

class Referee {
 public:
  /// Validates the options (throws Error).
  explicit Referee(const RefereeOptions& options = {});
  /// One period. Non-finite samples are skipped (the plant reports its faults itself).
  void observe(const RefereeSample& sample) noexcept;
  RefereeReport report() const noexcept;
  const RefereeOptions& options() const noexcept { return options_; }

 private:
  void closeOnset() noexcept;

  RefereeOptions options_;
  // Chatter filter: second-order Butterworth high-pass, coefficients for period filter_dt_.
  double filter_dt_ = 0.0, b0_ = 0.0, b1_ = 0.0, b2_ = 0.0, a1_ = 0.0, a2_ = 0.0;
  double x1_ = 0.0, x2_ = 0.0, y1_ = 0.0, y2_ = 0.0;
  // Session.
  std::uint64_t samples_ = 0, contacts_ = 0, contact_samples_ = 0, hold_samples_ = 0, onsets_ = 0;
  std::uint64_t saturated_samples_ = 0, turned_samples_ = 0;
  double seconds_ = 0.0, max_depth_ = 0.0, generated_ = 0.0;
  double stiffness_fd_ = 0.0, stiffness_dd_ = 0.0;  // sum f d, sum d^2 over the holds
  double rate_hardness_sum_ = 0.0, error_sq_ = 0.0, chatter_sq_ = 0.0;
  double peak_user_ = 0.0, peak_applied_ = 0.0;
  bool have_previous_ = false;
  Vec3 previous_position_ = Vec3::Zero();
  // The contact under way.
  bool in_contact_ = false;
  Vec3 entry_ = Vec3::Zero(), normal_ = Vec3::UnitZ();
  double contact_age_ = 0.0, onset_speed_ = 0.0, onset_max_rise_ = 0.0, previous_normal_force_ = 0.0;
  bool onset_open_ = false;
};

/// Where a session's referee publishes its report: made by whoever wants the figures (a CHAI3D
/// device, a tool) and handed to the joint I/O, which feeds it from the plant's thread. It outlives
/// the sessions: the last report stays readable after close().
class RefereeChannel {
 public:
  explicit RefereeChannel(const RefereeOptions& options = {}) : options_(options) { options_.validate(); }
  const RefereeOptions& options() const noexcept { return options_; }
  /// The plant's thread (one writer at a time; a new session's plant takes over at its start).
  void publish(const RefereeReport& report) noexcept { exchange_.write(report); }
  /// Any thread: the newest report (readers take turns; the writer never waits for them).
  RefereeReport latest() const;

 private:
  RefereeOptions options_;
  mutable TripleBuffer<RefereeReport> exchange_;
  mutable std::mutex readers_;
  mutable RefereeReport last_;
};

/// A simulated device with its referee: forwards everything to the plant, takes the scene's force
/// (setSceneForce) and after each advance() observes the plant's truth and publishes the report.
/// A plant without truth (readTruth() false) is forwarded unobserved.
class RefereedPlant final : public BoardPlant {
 public:
  /// Publishes an empty report at once: the channel then speaks of this session.
  RefereedPlant(std::unique_ptr<BoardPlant> plant, std::shared_ptr<RefereeChannel> channel);

  int jointCount() const noexcept override { return plant_->jointCount(); }
  int actuatorCount() const noexcept override { return plant_->actuatorCount(); }
  void readJoints(double* positions) noexcept override { plant_->readJoints(positions); }
  void applyCommand(const double* efforts) noexcept override { plant_->applyCommand(efforts); }
  void advance(double dt) noexcept override;
  bool readUserPoint(Vec3& position, Vec3& velocity) noexcept override { return plant_->readUserPoint(position, velocity); }
  void setUserForce(const Vec3& force) noexcept override { plant_->setUserForce(force); }
  Fault lastFault() const noexcept override { return plant_->lastFault(); }
  bool readTruth(PlantTruth& truth) noexcept override { return plant_->readTruth(truth); }
  void setSceneForce(const Vec3& force) noexcept override { asked_ = force.allFinite() ? force : Vec3::Zero(); }

 private:
  std::unique_ptr<BoardPlant> plant_;
  std::shared_ptr<RefereeChannel> channel_;
  Referee referee_;
  Vec3 asked_ = Vec3::Zero();
};

}  // namespace uhaptics
