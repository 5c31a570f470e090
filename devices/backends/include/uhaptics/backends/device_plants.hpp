#pragma once
// The three devices' simulated backends seen as what their controller boards drive (BoardPlant), so
// the board emulator speaks the wire protocol on top of the real device simulation, and the same
// adapters serve as the "sim" joint I/O (joint_io.hpp). Channels follow the board's STATE/COMMAND
// layout:
//
//   finger exoskeleton  joints (l_x [m], q_B [rad]), actuator force on l_x [N]   ExoFingerSim
//   TAU                 6 joint angles [rad], 6 joint torques [N m]             SimulatedTau
//   RHI planar          4 joint angles [rad], 4 joint torques [N m]             SimulatedPlanarLinkage<4>
//
// Each adapter owns its model and simulation and a user: the exoskeleton's finger follows a
// synthesized flexion-extension trajectory (position-driven, as in paper 000's Fig. 4); the TAU and
// the RHI are held at their home pose by a hand modelled as a spring-damper at the tool (TAU:
// paper 001's k_h, b_h; RHI: the grip of the paper 003 palpation set-up). advance(dt) steps the
// simulation in whole periods of its own rate and carries the remainder, so the board may call it
// with any dt (its clock is the wall clock). Allocation-free and noexcept after construction.
#include <memory>
#include <string>

#include "uhaptics/backends/board_plant.hpp"
#include "uhaptics/backends/exo_finger_sim.hpp"
#include "uhaptics/backends/simulated_planar_linkage.hpp"
#include "uhaptics/backends/simulated_tau.hpp"
#include "uhaptics/models/exo_finger_model.hpp"
#include "uhaptics/models/planar_linkage_model.hpp"
#include "uhaptics/models/tau_model.hpp"

namespace uhaptics {

/// Turns an arbitrary elapsed time into whole simulation steps of a fixed period. At most
/// max_catch_up seconds of simulation are due per call; an older backlog is dropped (the simulated
/// device then runs behind the wall clock), so a simulation slower than real time (a sanitizer
/// build, a stalled machine) cannot spiral into ever longer catch-up calls.
class FixedStepClock {
 public:
  /// Throws Error unless period and max_catch_up are finite and period > 0, max_catch_up >= period.
  explicit FixedStepClock(double period, double max_catch_up = 0.02);
  /// Adds dt (negative or non-finite dt is ignored) and returns how many whole periods are due.
  long take(double dt) noexcept;
  double period() const noexcept { return period_; }
  /// Simulation time dropped so far [s].
  double dropped() const noexcept { return dropped_; }

 private:
  double period_;
  long max_steps_;
  double pending_ = 0.0;
  double dropped_ = 0.0;
};

class ExoFingerBoardPlant final : public BoardPlant {
 public:
  struct Options {
    double sample_rate_hz = 1000.0;   // simulation step = the board's sampling (paper 000: 1 kHz)
    double duration_s = 600.0;        // finger trajectory length; held at its end afterwards
    double flexion_period_s = 4.0;    // one slow flexion-extension cycle of the MCP joint
    double trajectory_rate_hz = 200.0;  // trajectory samples (interpolated linearly in between)
  };
  /// Throws Error on invalid options (see ExoFingerSim, FingerTrajectory).
  ExoFingerBoardPlant(ExoFingerModel model, const Options& options);

  int jointCount() const noexcept override { return ExoFingerModel::kJoints; }
  int actuatorCount() const noexcept override { return ExoFingerModel::kActuated; }
  void readJoints(double* positions) noexcept override;
  void applyCommand(const double* efforts) noexcept override;
  void advance(double dt) noexcept override;

  const ExoFingerModel& model() const noexcept { return *model_; }
  const ExoFingerSim& sim() const noexcept { return sim_; }

 private:
  std::unique_ptr<const ExoFingerModel> model_;  // the simulation keeps a reference
  ExoFingerSim sim_;
  FixedStepClock clock_;
};

/// Plants whose joints are all actuated, with the torque held between updates (TAU, RHI).
template <int N>
class HeldTorquePlant : public BoardPlant {
 public:
  int jointCount() const noexcept override { return N; }
  int actuatorCount() const noexcept override { return N; }
  void readJoints(double* positions) noexcept override {
    Eigen::Map<Vec<N>> out(positions);
    out = sensed();
  }
  void applyCommand(const double* efforts) noexcept override { command_ = Eigen::Map<const Vec<N>>(efforts); }

 protected:
  virtual const Vec<N>& sensed() const noexcept = 0;
  Vec<N> command_ = Vec<N>::Zero();
};

class TauBoardPlant final : public HeldTorquePlant<6> {
 public:
  struct Options {
    HandModel hand;                   // spring-damper holding the tool at the home pose
    bool quantize = true;             // 4096-count encoders
    // The simulated handle's rotational damping [N m s/rad], as cTauDevice's default: the hand holds
    // only the tool's position, and the host's command arrives 1-2 sample periods after the reading
    // it was computed from (COMMAND/STATE exchange), which the undamped orientation does not
    // tolerate (0.38 rad in 3 s with a 1-period delay, divergence with 2; README "Hardware path").
    double tool_rotational_damping = 0.01;
  };
  TauBoardPlant(TauModel model, const Options& options);
  void advance(double dt) noexcept override;

  const TauModel& model() const noexcept { return *model_; }
  const SimulatedTau& sim() const noexcept { return sim_; }
  /// Faults the simulation reported (forward kinematics failing: the state is then held).
  long faults() const noexcept { return faults_; }

 private:
  const Vec6& sensed() const noexcept override { return sim_.encoderReading(); }
  std::unique_ptr<const TauModel> model_;
  SimulatedTau sim_;
  FixedStepClock clock_;
  long faults_ = 0;
};

class RhiBoardPlant final : public HeldTorquePlant<4> {
 public:
  struct Options {
    double substep = 1e-4;            // integration step [s]
    double hand_stiffness = 800.0;    // grip holding the end effector at home [N/m]
    double hand_damping = 8.0;        // [N s/m]
  };
  RhiBoardPlant(Rhi4Model model, const Options& options);
  void advance(double dt) noexcept override;

  const SimulatedPlanarLinkage<4>& sim() const noexcept { return sim_; }

 private:
  const Vec<4>& sensed() const noexcept override { return sim_.position(); }
  SimulatedPlanarLinkage<4> sim_;
  FixedStepClock clock_;
};

}  // namespace uhaptics
