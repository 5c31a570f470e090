#pragma once
// The joint-space core of the TAU's LQR wall (paper 001, eq. 11): the gains it runs on and the
// regulator (observer, integral states, commands in flight). Servo-rate, allocation-free. The gains
// come from designLqrWall (tau_wall_design.hpp).
#include "uhaptics/core/types.hpp"
#include "uhaptics/renderers/joint_disturbance_observer.hpp"

namespace uhaptics {

/// Largest command delay (whole servo periods) a wall design can account for; the regulator's
/// buffers are sized for it, so the servo tick stays allocation-free.
constexpr int kMaxCommandDelay = 4;

/// What LqrJointRegulator runs on: u = -Kc e - Ki x_i - Kd (commands in flight - u0), and its observer.
struct LqrWallGains {
  Mat<6, 12> Kc = Mat<6, 12>::Zero();  // on (qdot, q)
  Mat6 Ki = Mat6::Zero();              // on the integral of (r - q)
  Mat6 Ki_inverse = Mat6::Zero();      // for bumpless entry
  // Delay-aware design (command_delay D > 0): the plant applies the command of D periods ago, and
  // Kd (first 6 D columns) acts on the commands in flight (u_{k-1} - u0, ..., u_{k-D} - u0).
  int command_delay = 0;
  // Random-delay design: the plant applies u_{k-d}, d ~ U{0..command_delay} i.i.d. each period
  // (Kd on command_delay queued commands; the observer is fed the applied command the device
  // reports, or else the expected one).
  bool random_command_delay = false;
  Mat<6, 6 * kMaxCommandDelay> Kd = Mat<6, 6 * kMaxCommandDelay>::Zero();
  double period = 1e-3;                  // s, the servo period designed for
  Vec6 operating_torque = Vec6::Zero();  // u0: gravity at the operating point (linearization input)
  // Designed once (designLqrWall); a gain-only redesign (redesignLqrWallGains) keeps it unchanged.
  JointDisturbanceObserver::Gains observer;
};

/// The joint-space core of the LQR wall: observer + integral states + u = -Kc e - Ki x_i.
/// Allocation-free; used by the wall renderer and by the step-reference/force-step checks.
class LqrJointRegulator {
 public:
  explicit LqrJointRegulator(const LqrWallGains& gains) : gains_(gains), observer_(gains.observer) {
    for (Vec6& c : commands_) c.setZero();
  }
  void setGains(const LqrWallGains& gains) noexcept {
    gains_ = gains;
    observer_.setGains(gains.observer);
  }
  /// Observer at rest at the measured joints, integrator cleared.
  void reset(const Vec6& q_measured) noexcept;
  /// Observer update with the new measurement q_measured [rad] (call once per tick, before control()).
  /// `applied`: the torque [N m] the device reports it applied over the last period (a board echoes the
  /// sequence number of the command it applied); nullptr: inferred from the delay model (the
  /// command of command_delay periods ago, or for a random delay the mean of those it may have been).
  void observe(const Vec6& q_measured, const Vec6* applied = nullptr) noexcept;
  /// The torque [N m] actually commanded this tick (after saturation): queued as a command in flight.
  void applied(const Vec6& torque) noexcept {
    head_ = (head_ + 1) % kHistory;
    commands_[head_] = torque;
  }
  Vec6 velocity() const noexcept { return observer_.velocity(); }
  Vec6 position() const noexcept { return observer_.position(); }
  Vec6 disturbance() const noexcept { return observer_.disturbance(); }
  /// -Kc e - Ki x_i - Kd (commands in flight - u0) [N m] for the error e = (qdot - qdot_ref [rad/s],
  /// q - r [rad]).
  Vec6 control(const Vec<12>& error) const noexcept { return -gains_.Kc * error - gains_.Ki * integral_ - inFlightTerm(); }
  /// x_i += T (r - q) = -T (q - r).
  void integrate(const Vec6& position_error) noexcept { integral_ -= gains_.period * position_error; }
  /// Bumpless start: x_i such that control(error) = 0.
  void startBumpless(const Vec<12>& error) noexcept {
    integral_ = -gains_.Ki_inverse * (gains_.Kc * error + inFlightTerm());
  }
  void clearIntegral() noexcept { integral_.setZero(); }
  const Vec6& integral() const noexcept { return integral_; }
  const LqrWallGains& gains() const noexcept { return gains_; }
  const JointDisturbanceObserver& observer() const noexcept { return observer_; }

 private:
  static constexpr int kHistory = kMaxCommandDelay + 1;
  /// The command issued `samples_ago` ticks ago (1: the last one), 1 <= samples_ago <= kHistory.
  const Vec6& commanded(int samples_ago) const noexcept { return commands_[(head_ + kHistory + 1 - samples_ago) % kHistory]; }
  Vec6 inFlightTerm() const noexcept;
  LqrWallGains gains_;  // the observer runs on its own copy of gains_.observer
  JointDisturbanceObserver observer_;
  Vec6 integral_ = Vec6::Zero();
  Vec6 commands_[kHistory];  // ring buffer of the last kHistory commands, newest at head_
  int head_ = 0;
};

}  // namespace uhaptics
