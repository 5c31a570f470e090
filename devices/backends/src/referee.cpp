#include "uhaptics/backends/referee.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "uhaptics/core/fault.hpp"

namespace uhaptics {

namespace {
bool positiveFinite(double v) { return v > 0.0 && std::isfinite(v); }
}  // namespace

void RefereeOptions::validate() const {
  const struct {
    const char* name;
    double value;
  } fields[] = {{"contact_force", contact_force},   {"onset_window", onset_window},
                {"min_onset_speed", min_onset_speed}, {"hold_speed", hold_speed},
                {"min_hold_depth", min_hold_depth}, {"chatter_cutoff_hz", chatter_cutoff_hz},
                {"max_normal_turn", max_normal_turn}};
  for (const auto& f : fields)
    if (!positiveFinite(f.value))
      throw Error(std::string("referee option ") + f.name + " must be finite and > 0, not " + std::to_string(f.value));
  if (max_normal_turn > M_PI) throw Error("referee option max_normal_turn must be at most pi");
}

Referee::Referee(const RefereeOptions& options) : options_(options) { options_.validate(); }

void Referee::closeOnset() noexcept {
  if (!onset_open_) return;
  onset_open_ = false;
  if (onset_speed_ >= options_.min_onset_speed && onset_max_rise_ > 0.0) {
    rate_hardness_sum_ += onset_max_rise_ / onset_speed_;
    ++onsets_;
  }
}

void Referee::observe(const RefereeSample& s) noexcept {
  const PlantTruth& t = s.truth;
  if (!positiveFinite(s.dt) || !t.position.allFinite() || !t.velocity.allFinite() || !t.user_force.allFinite() ||
      !t.applied_force.allFinite() || !s.asked_force.allFinite())
    return;
  const double dt = s.dt;
  ++samples_;
  seconds_ += dt;
  // The user's force is held over the period, so its work is exactly F . dx.
  if (have_previous_) generated_ -= t.user_force.dot(t.position - previous_position_);
  const Vec3 before = have_previous_ ? previous_position_ : t.position;
  previous_position_ = t.position;
  have_previous_ = true;
  peak_user_ = std::max(peak_user_, t.user_force.norm());
  peak_applied_ = std::max(peak_applied_, t.applied_force.norm());

  const double asked = s.asked_force.norm();
  if (!in_contact_ && asked > options_.contact_force) {
    in_contact_ = true;
    ++contacts_;
    entry_ = before;  // the last position the scene asked nothing at: the surface lies beyond it
    normal_ = s.asked_force / asked;  // outward: the scene pushes the tool out of its surface
    contact_age_ = 0.0;
    onset_speed_ = -t.velocity.dot(normal_);
    onset_max_rise_ = 0.0;
    onset_open_ = true;
    previous_normal_force_ = t.applied_force.dot(normal_);
    // The high-pass starts settled on the present force (it passes no constant).
    x1_ = x2_ = previous_normal_force_;
    y1_ = y2_ = 0.0;
  } else if (in_contact_ && asked < 0.5 * options_.contact_force) {
    closeOnset();
    in_contact_ = false;
  }
  if (!in_contact_) return;

  ++contact_samples_;
  contact_age_ += dt;
  error_sq_ += (t.applied_force - s.asked_force).squaredNorm();
  if (t.saturated) ++saturated_samples_;
  // The entry plane describes the surface while the scene's force keeps its direction; once the tool
  // has slid round a curve (a tooth's flank) the depth along the old normal would count the slide.
  const bool planar = s.asked_force.dot(normal_) >= std::cos(options_.max_normal_turn) * asked;
  if (!planar) ++turned_samples_;
  const double depth = (entry_ - t.position).dot(normal_);
  if (planar) max_depth_ = std::max(max_depth_, depth);

  const double normal_force = t.applied_force.dot(normal_);
  if (dt != filter_dt_) {
    // Bilinear transform of the second-order Butterworth high-pass.
    const double k = std::tan(M_PI * std::min(options_.chatter_cutoff_hz * dt, 0.49));
    const double norm = 1.0 / (1.0 + M_SQRT2 * k + k * k);
    b0_ = norm;
    b1_ = -2.0 * norm;
    b2_ = norm;
    a1_ = 2.0 * (k * k - 1.0) * norm;
    a2_ = (1.0 - M_SQRT2 * k + k * k) * norm;
    filter_dt_ = dt;
  }
  const double high = b0_ * normal_force + b1_ * x1_ + b2_ * x2_ - a1_ * y1_ - a2_ * y2_;
  x2_ = x1_;
  x1_ = normal_force;
  y2_ = y1_;
  y1_ = high;

  if (onset_open_) {
    if (contact_age_ <= options_.onset_window + 0.5 * dt) {
      onset_max_rise_ = std::max(onset_max_rise_, (normal_force - previous_normal_force_) / dt);
    } else {
      closeOnset();
    }
  }
  previous_normal_force_ = normal_force;

  const bool hold = planar && contact_age_ > options_.onset_window && std::abs(t.velocity.dot(normal_)) < options_.hold_speed &&
                    depth > options_.min_hold_depth;
  if (!hold) return;
  ++hold_samples_;
  const double push = -t.user_force.dot(normal_);  // the user's push into the surface
  stiffness_fd_ += push * depth;
  stiffness_dd_ += depth * depth;
  chatter_sq_ += high * high;
}

RefereeReport Referee::report() const noexcept {
  RefereeReport r;
  r.samples = samples_;
  r.seconds = seconds_;
  r.contacts = contacts_;
  r.contact_samples = contact_samples_;
  r.hold_samples = hold_samples_;
  r.turned_samples = turned_samples_;
  r.onset_samples = onsets_;
  r.max_true_penetration_mm = 1e3 * max_depth_;
  r.generated_energy_mJ = 1e3 * generated_;
  r.peak_user_force_N = peak_user_;
  r.peak_applied_force_N = peak_applied_;
  if (stiffness_dd_ > 0.0) r.rendered_stiffness_N_per_m = stiffness_fd_ / stiffness_dd_;
  if (onsets_ > 0) r.rate_hardness_N_per_m = rate_hardness_sum_ / static_cast<double>(onsets_);
  if (contact_samples_ > 0) {
    const double n = static_cast<double>(contact_samples_);
    r.force_error_rms_N = std::sqrt(error_sq_ / n);
    r.saturated_share = static_cast<double>(saturated_samples_) / n;
  }
  if (hold_samples_ > 0) r.chatter_N = std::sqrt(chatter_sq_ / static_cast<double>(hold_samples_));
  return r;
}

RefereeReport RefereeChannel::latest() const {
  const std::lock_guard<std::mutex> lock(readers_);
  exchange_.read(last_);
  return last_;
}

RefereedPlant::RefereedPlant(std::unique_ptr<BoardPlant> plant, std::shared_ptr<RefereeChannel> channel)
    : plant_(std::move(plant)), channel_(std::move(channel)), referee_(channel_ ? channel_->options() : RefereeOptions{}) {
  if (!plant_ || !channel_) throw Error("RefereedPlant needs a plant and a channel");
  channel_->publish(referee_.report());
}

void RefereedPlant::advance(double dt) noexcept {
  plant_->advance(dt);
  RefereeSample sample;
  if (!plant_->readTruth(sample.truth)) return;
  sample.dt = dt;
  sample.asked_force = asked_;
  referee_.observe(sample);
  channel_->publish(referee_.report());
}

}  // namespace uhaptics
