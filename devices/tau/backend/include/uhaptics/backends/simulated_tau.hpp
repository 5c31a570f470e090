#pragma once
// Simulated TAU: integrates the lumped dynamic model at a finer step than the 1 kHz controller,
// with joint torque saturation, encoder quantization, an optional random transport delay of the
// command (0..N whole samples, as in paper 001's CoS-D runs), optional mechanical damping at the
// tool (the baseline's 4 Ns/m, translational and rotational), optional mechanical end stops (the
// model's TauModel::EndStops) and a hand model (spring-damper between the tool and a moving hand).
//
// Multi-rate integration: the configuration-dependent terms (forward kinematics, J, M, gravity,
// velocity terms) are refreshed once per servo period; the substeps integrate with them frozen
// (semi-implicit Euler), tracking the tool by first-order kinematics. At the speeds of a wall
// contact (< 0.1 m/s) the configuration moves < 0.1 mm per period, so freezing them changes the
// result far less than the encoder quantization (tests/tau/simulated_tau_test.cpp checks both the
// refresh and the substep; docs/tau.md, "Simulated device", has the figures).
#include <cstdint>
#include <Eigen/Cholesky>
#include <random>
#include <vector>

#include "uhaptics/core/fault.hpp"
#include "uhaptics/core/types.hpp"
#include "uhaptics/models/tau_model.hpp"

namespace uhaptics {

struct HandModel {
  double stiffness = 40.0;  // k_h, N/m (paper 001, after its ref. [34])
  double damping = 3.6;     // b_h, N s/m
};

struct SimulatedTauOptions {
  int substeps = 0;               // per period; 0: the model file's rates/simulation_substeps
  // One step() [s]: the servo period the simulation is driven at. 0: the model's servo period (its
  // board's 1 kHz); shorter for a faster servo loop (the Z-width harness's 2-4 kHz), where the
  // configuration-dependent terms are then refreshed at that rate too.
  double period = 0.0;
  int max_delay_samples = 0;      // command delay drawn uniformly from 0..max each sample
  double tool_damping = 0.0;      // mechanical damping at the tool, translational, N s/m
  double tool_rotational_damping = 0.0;  // on the tool's orientation (Euler-angle) rates, N m s/rad
  bool quantize = true;           // encoder quantization (false: ideal sensor, for design checks)
  // The device's mechanical stops (TauModel::endStops()). Off for paper 001's study, whose runs stay
  // in the workspace; on where the device may go unpowered (a board plant, a fault).
  bool end_stops = false;
  // The plant's lumped dynamics (M, gravity, velocity term), J and dg/dX's factorization are solved
  // again when any joint has moved more than this (rad) since they last were; within it they are
  // held (they change by about the tolerance, relatively), and the pose is still solved to the
  // forward kinematics' tolerance with the held factorization. 0: solved every period. In [0, 0.1].
  double relinearize_tolerance = 0.0;
  std::uint64_t seed = 1;         // delay draws
  HandModel hand;
};

class SimulatedTau {
 public:
  /// Starts at rest at the model's home joints; keeps a reference to model (it must outlive the
  /// simulation). Throws uhaptics::Error when an option is out of range (substeps 1..1000 after the
  /// file's default, period not in [0, 0.1] s, max_delay_samples 0..100, negative damping or hand parameters,
  /// relinearize_tolerance outside [0, 0.1]) or the forward kinematics fails at home.
  SimulatedTau(const TauModel& model, const SimulatedTauOptions& options);
  /// At rest at joint angles q0 [rad] (throws Error if the forward kinematics fails there).
  void reset(const Vec6& q0);

  /// Hand attached with position/velocity/acceleration at the start of the next period (the hand
  /// moves with constant acceleration within it). Without a hand, only the external force acts.
  void setHand(const Vec3& position, const Vec3& velocity, const Vec3& acceleration) noexcept;
  void detachHand() noexcept { hand_attached_ = false; }

  /// One servo period with command tau [N m] (saturated here) and an external tool force [N] held
  /// constant over the period. Returns a Fault if the model fails: before the period, the state is left
  /// unchanged; at its end (the joints would leave the range where the mechanism assembles), the
  /// joints stay where they were and stop, as against a geometric stop, and time advances.
  Fault step(const Vec6& tau_command, const Vec3& external_force) noexcept;

  const Vec6& encoderReading() const noexcept { return reading_; }
  const Vec6& q() const noexcept { return q_; }
  const Vec6& qd() const noexcept { return qd_; }
  const Vec6& pose() const noexcept { return data_.pose; }
  Vec3 toolVelocity() const noexcept { return data_.J.topRows<3>() * qd_; }
  /// Hand force on the tool, averaged over the last period (what the user feels as a load).
  const Vec3& handForce() const noexcept { return hand_force_; }
  const Vec6& appliedTorque() const noexcept { return applied_; }
  /// Which command the last step() applied: how many step() calls before that step's own command it
  /// came (0..max_delay_samples), as a board names the command it applied by its sequence number.
  int appliedDelay() const noexcept { return applied_delay_; }
  /// The force [N] the applied torques exert at the tool in statics beyond holding up the mechanism's
  /// own weight: the translational part of w in J^T w = tau_applied - g(q), at the last step's
  /// configuration. What a user holding the tool still feels (the referee's applied force).
  Vec3 toolForce() const noexcept;
  double time() const noexcept { return time_; }
  /// One step()'s length [s] (SimulatedTauOptions::period, resolved).
  double period() const noexcept { return options_.period; }
  const TauModel& model() const noexcept { return model_; }

 private:
  void quantize() noexcept;
  Fault linearize() noexcept;
  const TauModel& model_;
  SimulatedTauOptions options_;
  TauData data_;
  Vec6 q_ = Vec6::Zero(), qd_ = Vec6::Zero(), reading_ = Vec6::Zero(), applied_ = Vec6::Zero();
  int applied_delay_ = 0;
  std::vector<Vec6> command_history_;  // ring buffer of the last max_delay + 1 commands
  std::size_t history_head_ = 0;
  bool started_ = false;  // a command has been applied since reset()
  std::mt19937_64 rng_;
  bool hand_attached_ = false;
  Vec3 hand_p_ = Vec3::Zero(), hand_v_ = Vec3::Zero(), hand_a_ = Vec3::Zero(), hand_force_ = Vec3::Zero();
  double time_ = 0.0;
  // The period's dynamics, solved at q_lin_ (pose pose_lin_) and held while the joints stay within
  // relinearize_tolerance of it: M's factorization and M^-1 applied to the force directions.
  bool linearized_ = false;
  Vec6 q_lin_ = Vec6::Zero(), pose_lin_ = Vec6::Zero();
  Eigen::LLT<Mat6> mass_;
  Mat<6, 3> force_to_qdd_ = Mat<6, 3>::Zero(), torque_to_qdd_ = Mat<6, 3>::Zero();
  Mat6 rotational_damping_ = Mat6::Zero();
};

}  // namespace uhaptics
