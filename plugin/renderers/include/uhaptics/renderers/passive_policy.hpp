#pragma once
// uhaptics::PassivePolicy: the passivity layer in the servo path. It wraps any device's rendering
// policy (device_policy.hpp) and runs the scene-port observer and controller (ScenePortPassivity,
// scene_port_passivity.hpp) on the device's actuated joints, so the share of the command that
// renders the scene never gives the user more energy than the scene itself would in continuous
// time, whatever the sampling and the command delay make of it.
//
// One servo period:
//
//   sense(reading)  the wrapped policy's sense(); the actuated joints' positions are kept
//   render(input)   the wrapped policy's efforts e and their scene share s = e - ownEfforts();
//                   the layer closes the last period with the port effort the board applied over it
//                   (sent command_delay periods earlier, as reset() was told), books its work
//                   against the scene's trapezoidal work, and where the port generated energy it
//                   brakes along s on the last period's displacement; the command is held to the
//                   effort limits and finite
//
// The policy's own fields (gravity compensation, null-space control, the LQR wall's regulator)
// are neither observed nor damped: with no scene force the layer adds nothing. Joint convention:
// actuator i drives sensed joint i, the sensed-only joints following the actuated ones.
//
// Periods this layer did not command are left out of the observation (the chain starts again and
// the excess is forgotten; the totals stay): a period without a reading (readingLost()), a reading
// that got no render() (the caller's stale-input ramp), a new session (reset(), a first reading). A
// period whose wrapped render() faults is commanded zero and ends the chain the same way.
//
// Figures (FigureRecorder; energies in mJ, damping in N m s/rad, or N s/m on a prismatic joint):
//   passivity_energy_out_mJ       net work the scene's port (its share plus the layer's damping, as
//                                 applied) did on the user (value; it falls when the user presses in)
//   passivity_generated_mJ        energy the port generated against the continuous-time scene (value)
//   passivity_peak_excess_mJ      the most generated energy that waited for dissipation (maximum)
//   passivity_dissipated_mJ       work the layer's damping took from the user (value)
//   passivity_active_ticks        periods in which damping was added
//   passivity_max_damping         largest damping added along the scene's effort
//   passivity_faults              periods the layer refused (non-finite reading or efforts, bad
//                                 period) and commanded zero
//
// Threading and cost as DevicePolicy: sense(), render(), readingLost() and endSession() never
// allocate, throw or block; construction, configure() and reset() are set-up.
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "uhaptics/core/scene_port_passivity.hpp"
#include "uhaptics/renderers/device_policy.hpp"

namespace uhaptics {

class PassivePolicy final : public DevicePolicy {
 public:
  using Controller = ScenePortPassivity;

  struct Options {
    /// Actuated joints: the first `actuators` sensed joints, 1..kMaxSensedJoints.
    int actuators = 1;
    /// The observer and controller on the actuated joints (scene_port_passivity.hpp): enabled =
    /// false observes only (efforts pass bit for bit). Its command_delay is overridden by reset()'s.
    ScenePortPassivityOptions controller;
  };

  /// Takes over `wrapped` and declares this layer's figures on `figures` (which must outlive it).
  /// Throws uhaptics::Error when wrapped is null, actuators is outside 1..kMaxSensedJoints, a
  /// controller option is out of range, or the recorder refuses a figure (full, or a name taken).
  PassivePolicy(std::unique_ptr<DevicePolicy> wrapped, const Options& options, FigureRecorder& figures);

  /// Set-up, between sessions: new options (e.g. the effort limits and inertia of the board just
  /// opened); the observation starts again. Throws uhaptics::Error as the constructor.
  void configure(const Options& options);

  /// The wrapped policy's name, followed by " + passivity".
  std::string name() const override;
  /// Also aligns the layer's booking with command_delay (0..kScenePortMaxDelay; throws beyond).
  void reset(int command_delay) override;
  void sense(const SensedJoints& reading, SensedState& state) noexcept override;
  void checkFirstReading() const override { wrapped_->checkFirstReading(); }
  Fault render(const SceneInput& input, double* efforts) noexcept override;
  void readingLost() noexcept override;
  void endSession() noexcept override;
  void commandApplied(int periods_ago) noexcept override { wrapped_->commandApplied(periods_ago); }
  /// The wrapped policy's own fields: the layer's damping is the scene port's.
  void ownEfforts(double* efforts) const noexcept override { wrapped_->ownEfforts(efforts); }
  bool actuatedInertia(double* inertia) const override { return wrapped_->actuatedInertia(inertia); }
  Vec3 deviceToModelForce(const Vec3& force) const noexcept override { return wrapped_->deviceToModelForce(force); }
  Vec3 sceneForceAtUserPort(const Vec3& force) const noexcept override { return wrapped_->sceneForceAtUserPort(force); }
  Vec3 modelToDevicePoint(const Vec3& point) const noexcept override { return wrapped_->modelToDevicePoint(point); }
  Vec3 modelToDeviceVector(const Vec3& vector) const noexcept override { return wrapped_->modelToDeviceVector(vector); }

  DevicePolicy& wrapped() noexcept { return *wrapped_; }
  const DevicePolicy& wrapped() const noexcept { return *wrapped_; }
  const Options& options() const noexcept { return options_; }
  /// The observer and controller: booked work, generated energy, excess, dissipated, ticks, faults.
  const Controller& controller() const noexcept { return controller_; }

 private:
  static Controller makeController(const Options& options);
  void recordFigures(std::uint64_t active_before, Fault fault) noexcept;

  std::unique_ptr<DevicePolicy> wrapped_;
  Options options_;
  Controller controller_;
  FigureRecorder& figures_;
  Controller::Vector q_, efforts_, scene_, command_;  // the actuated joints' reading, efforts, scene share
  bool sensed_ = false;  // a reading is waiting for its render()
  int fig_energy_ = 0, fig_generated_ = 0, fig_peak_excess_ = 0, fig_dissipated_ = 0, fig_active_ = 0,
      fig_max_damping_ = 0, fig_faults_ = 0;
};

/// The layer's options for a device's policy: `board` (the effort limits and sensor steps of the
/// board it runs on, boardPassivityOptions) with the joint-space inertia of the actuated joints from
/// policy.actuatedInertia() at rest_joints (a policy without dynamics: none, and the layer observes
/// only unless board.max_damping is set). The one set-up the CHAI3D adapter and the harnesses share.
/// Leaves the policy sensing rest_joints, at rest. Set-up: allocates; throws Error for joints outside
/// 1..kMaxSensedJoints or actuators outside 1..joints.
PassivePolicy::Options passivePolicyOptions(DevicePolicy& policy, const double* rest_joints, int joints, int actuators,
                                            const ScenePortPassivityOptions& board);

}  // namespace uhaptics
