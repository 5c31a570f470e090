#pragma once
// uhaptics::PassivePolicy: the passivity layer in the servo path. It wraps any device's rendering
// policy (device_policy.hpp) and runs the time-domain passivity observer and controller
// (PassivityController, Hannaford and Ryu 2002) on the device's actuated joints, so the device never
// gives out more energy than it has taken in, whatever the wrapped renderer asks for.
//
// One servo period:
//
//   sense(reading)  the wrapped policy's sense(); the actuated joints' positions and rates of the
//                   same reading are kept for the controller
//   render(input)   the wrapped policy's efforts u; the controller closes the last period with the
//                   work of the command actually applied, and where the device has given out more
//                   than it has taken in it adds -alpha qd (alpha capped per joint, nothing below the
//                   velocity guard); the command is held to the effort limits and finite
//
// Joint space, so that every device is covered: an underactuated device's sensed-only joints carry
// no effort and do no work, and a redundant device's null-space motion is work like any other.
// Joint convention: actuator i drives sensed joint i, the sensed-only joints following the actuated
// ones (the wire protocol's order, and every uhaptics device's).
//
// Periods this layer did not command are left out of the observation (the work across them is not
// counted; what was counted stays): a period without a reading (readingLost()), a reading that got
// no render() (the caller's stale-input ramp), a new session (reset(), a first reading). A period
// whose wrapped render() faults is commanded zero by the caller: the observer counts a zero command
// and the fault is passed on.
//
// Figures (FigureRecorder; energies in mJ, damping in N m s/rad, or N s/m on a prismatic joint):
//   passivity_energy_out_mJ       net energy the applied commands have given the user (value; it
//                                 falls when the user does work on the device)
//   passivity_peak_energy_out_mJ  its largest value: the observer's worst report of net generated
//                                 energy
//   passivity_dissipated_mJ       energy the added damping has absorbed (value)
//   passivity_active_ticks        periods in which damping was added
//   passivity_max_damping         largest damping added to one joint
//   passivity_faults              periods the controller refused (non-finite reading or efforts,
//                                 bad period) and commanded zero
//
// Threading and cost as DevicePolicy: sense(), render(), readingLost() and endSession() never
// allocate, throw or block; construction, configure() and reset() are set-up.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "uhaptics/core/passivity_controller.hpp"
#include "uhaptics/renderers/device_policy.hpp"

namespace uhaptics {

class PassivePolicy final : public DevicePolicy {
 public:
  using Controller = PassivityController<Eigen::Dynamic>;

  struct Options {
    /// Actuated joints: the first `actuators` sensed joints, 1..kMaxSensedJoints.
    int actuators = 1;
    /// The controller per actuated joint: enabled = false observes only (efforts pass bit for bit);
    /// max_damping / max_damping_per_joint cap the damping [N m s/rad or N s/m]; effort_limit holds
    /// the command [N m or N]; min_rate is the velocity guard [rad/s or m/s]. Sizes 0 or
    /// `actuators` (passivity_controller.hpp).
    PassivityControllerOptions<Eigen::Dynamic> controller;
  };

  /// Takes over `wrapped` and declares this layer's figures on `figures` (which must outlive it).
  /// Throws uhaptics::Error when wrapped is null, actuators is outside 1..kMaxSensedJoints, a
  /// controller option is out of range, or the recorder refuses a figure (full, or a name taken).
  PassivePolicy(std::unique_ptr<DevicePolicy> wrapped, const Options& options, FigureRecorder& figures);

  /// Set-up, between sessions: new options (e.g. the effort limits and guard of the board just
  /// opened); the observation starts again. Throws uhaptics::Error as the constructor.
  void configure(const Options& options);

  /// The wrapped policy's name, followed by " + passivity".
  std::string name() const override;
  void reset(int command_delay) override;
  void sense(const SensedJoints& reading, SensedState& state) noexcept override;
  void checkFirstReading() const override { wrapped_->checkFirstReading(); }
  Fault render(const SceneInput& input, double* efforts) noexcept override;
  void readingLost() noexcept override;
  void endSession() noexcept override;
  Vec3 deviceToModelForce(const Vec3& force) const noexcept override { return wrapped_->deviceToModelForce(force); }
  Vec3 sceneForceAtUserPort(const Vec3& force) const noexcept override { return wrapped_->sceneForceAtUserPort(force); }
  Vec3 modelToDevicePoint(const Vec3& point) const noexcept override { return wrapped_->modelToDevicePoint(point); }
  Vec3 modelToDeviceVector(const Vec3& vector) const noexcept override { return wrapped_->modelToDeviceVector(vector); }

  DevicePolicy& wrapped() noexcept { return *wrapped_; }
  const DevicePolicy& wrapped() const noexcept { return *wrapped_; }
  const Options& options() const noexcept { return options_; }
  /// The observer and controller: energy out, peak, dissipated, active ticks, faults, last damping.
  const Controller& controller() const noexcept { return controller_; }

 private:
  static Controller makeController(const Options& options);
  void recordFigures(std::uint64_t active_before, Fault fault) noexcept;

  std::unique_ptr<DevicePolicy> wrapped_;
  Options options_;
  Controller controller_;
  FigureRecorder& figures_;
  Controller::Vector q_, rates_, efforts_, command_;  // the actuated joints' reading and efforts
  bool sensed_ = false;  // a reading is waiting for its render()
  int fig_energy_ = 0, fig_peak_ = 0, fig_dissipated_ = 0, fig_active_ = 0, fig_max_damping_ = 0, fig_faults_ = 0;
};

/// Per actuated joint, the damping cap [N m s/rad or N s/m] under which the joint's added damping
/// puts at most linear_damping [N s/m] on the tool's motion and angular_damping [N m s/rad] on its
/// rotation: b_i = b_lin |dp/dq_i|^2 + b_ang |dtheta/dq_i|^2, the tool's sensitivities from central
/// differences of policy.sense() about rest_joints (its kinematics, whatever the device). A device's
/// specification states its damping at the tool (BoardSpec::max_linear_damping, CHAI3D's
/// m_maxLinearDamping); this turns it into the caps PassivityControllerOptions::max_damping_per_joint
/// takes. Non-positive or non-finite damping counts as 0. Leaves the policy sensing rest_joints, at
/// rest. Set-up: allocates; throws Error for joints outside 1..kMaxSensedJoints or actuators outside
/// 1..joints.
std::vector<double> passivityDampingCaps(DevicePolicy& policy, const double* rest_joints, int joints, int actuators,
                                         double linear_damping, double angular_damping);

}  // namespace uhaptics
