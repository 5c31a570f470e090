#pragma once
// The TAU's simulation as its board drives it: 6 joint angles [rad], 6 joint torques [N m]
// (SimulatedTau). Its user, by default: a hand modelled as a spring-damper holding the tool at the
// home pose (paper 001's k_h, b_h); without it, whoever calls setUserForce (a CHAI3D session's
// scripted hand).
#include <memory>

#include "uhaptics/backends/device_plants.hpp"
#include "uhaptics/backends/simulated_tau.hpp"
#include "uhaptics/models/tau_model.hpp"

namespace uhaptics {

class TauBoardPlant final : public HeldTorquePlant<6> {
 public:
  struct Options {
    HandModel hand;                   // spring-damper holding the tool at the home pose
    bool hold_tool = true;            // false: no hand of its own; setUserForce is the user
    double tool_damping = 0.0;        // mechanical damping at the tool [N s/m]
    bool quantize = true;             // 4096-count encoders
    bool end_stops = true;            // the device's mechanical stops (TauModel::endStops())
    // The simulated handle's rotational damping [N m s/rad], as cTauDevice's default: the hand holds
    // only the tool's position, and the host's command arrives 1-2 sample periods after the reading
    // it was computed from (COMMAND/STATE exchange), which the undamped orientation does not
    // tolerate: it drifts, and diverges with a 2-period delay (docs/hardware.md, "Why the emulated
    // TAU board damps the handle"). >= 0.
    double tool_rotational_damping = 0.01;
    // The simulation's step [s] (SimulatedTauOptions::period): 0, the model's servo period, at which
    // the board samples; shorter for a caller that runs its servo loop on the plant faster.
    double step_period = 0.0;
  };
  /// Starts at rest at the model's home joints. Throws uhaptics::Error on invalid options (see
  /// SimulatedTau) or when the model does not assemble at home.
  TauBoardPlant(TauModel model, const Options& options);
  void advance(double dt) noexcept override;
  bool readUserPoint(Vec3& position, Vec3& velocity) noexcept override {
    position = sim_.pose().head<3>();
    velocity = sim_.toolVelocity();
    return true;
  }
  void setUserForce(const Vec3& force) noexcept override { user_force_ = force; }
  /// The tool point; the user's force is the hand's (its own, when it holds the tool) plus the
  /// caller's (setUserForce); saturated when a motor is at its torque limit.
  bool readTruth(PlantTruth& truth) noexcept override;
  Fault lastFault() const noexcept override { return fault_; }

  const TauModel& model() const noexcept { return *model_; }
  const SimulatedTau& sim() const noexcept { return sim_; }
  /// Faults the simulation reported (forward kinematics failing: the state is then held).
  long faults() const noexcept { return faults_; }

 private:
  const Vec6& sensed() const noexcept override { return sim_.encoderReading(); }
  std::unique_ptr<const TauModel> model_;
  SimulatedTau sim_;
  FixedStepClock clock_;
  Vec3 user_force_ = Vec3::Zero();
  Fault fault_ = Fault::kNone;
  long faults_ = 0;
};

}  // namespace uhaptics
