#pragma once
// Design of the TAU's LQR wall (paper 001): weights, observer noise and command-delay model in, the
// gains LqrJointRegulator runs on out. Set-up code: it allocates and throws uhaptics::Error.
#include "uhaptics/core/types.hpp"
#include "uhaptics/models/tau_model.hpp"
#include "uhaptics/renderers/lqr_joint_regulator.hpp"

namespace uhaptics {

/// LQR weights: Q = diag(velocity I6, position I6, integral I6), R = torque I6, per unit squared of
/// the augmented state (qdot [rad/s], q [rad], integral of r - q [rad s]) and of the torque [N m].
/// velocity, position >= 0; integral, torque > 0 (designLqrWall throws otherwise).
/// Defaults: for our assumed TAU-class plant, paper 001's position and integral weights raised by
/// 1e3 (the paper's integral/position ratio 1e4 kept) to meet its 0.001 rad joint deflection
/// requirement under a 15 N push (with state feedback), and the velocity weight set so the fastest
/// pole stays near the paper's ~2480 rad/s (docs/tau.md, "LQR weights": why the paper's own
/// weights fall short on this plant).
struct LqrWallWeights {
  double velocity = 1.1;
  double position = 1e6;
  double integral = 1e10;
  double torque = 1.0;
  /// Paper 001's Q = diag(I6, 1e3 I6, 1e7 I6), R = I6.
  static LqrWallWeights paper() { return {1.0, 1e3, 1e7, 1.0}; }
};

/// Noise levels the observer (JointDisturbanceObserver: qdot, q and the disturbance torque d from
/// the quantized encoders) is designed for; the process noises must be > 0 (designLqrWall throws
/// otherwise).
struct ObserverNoise {
  double velocity_process = 1e-3;  // rad/s per sample (unmodelled accelerations)
  // N m per sample: how fast the user's push may change (the disturbance state's random walk). A
  // smaller value makes the observer slower to take up a push, so the wall sinks deeper and a force
  // step deflects the joints further (docs/tau.md, "Observer tuning").
  double disturbance_process = 0.05;
  double position_process = 1e-7;  // rad per sample (keeps the filter DARE well posed)
  double quantization = 0.0;       // encoder std (rad); 0: resolution / sqrt(12) of the model
};

/// The observer noise a device's wall uses under a fixed command delay of `command_delay` periods
/// (>= 0): the defaults, with a disturbance walk of 0.01 N m per sample once the command is
/// delayed. Seeing the user's push a period late, an estimate as fast as the undelayed one chases
/// the encoders' quantization into the torque limits (docs/tau.md, "What the scene sees of a
/// simulated TAU").
ObserverNoise observerNoiseForDelay(int command_delay) noexcept;

/// How the wall's LQR accounts for the command delay.
struct CommandDelayDesign {
  int samples = 0;           // fixed delay D, or the largest delay of the random model (<= kMaxCommandDelay)
  bool random = false;       // true: d ~ U{0..samples} drawn i.i.d. each period (generalized Riccati)
  double rate_weight = 0.0;  // weight on (u_k - u_{k-1})^2 per joint, (N m)^-2 (random model only)
};

/// What a wall design reports besides the gains: the point it was made at, the delay model, and
/// the checks on the synthesis. Nothing here is read at run time.
struct LqrWallDesignReport {
  Vec6 operating_pose = Vec6::Zero();
  Vec6 operating_joints = Vec6::Zero();
  CommandDelayDesign delay;          // the delay model designed for (a gain-only redesign keeps it)
  double fastest_pole_rad_s = 0.0;   // |s| of the fastest closed-loop pole (paper 001: ~2480 rad/s)
  double dare_residual = 0.0;        // relative residual of the control DARE (random delay: generalized Riccati)
  int dare_iterations = 0;
  double ms_spectral_radius = 0.0;   // mean-square closed-loop radius of the random-delay design (< 1: stable)
};

struct LqrWallDesign {
  LqrWallGains gains;  // what the regulator runs on
  LqrWallDesignReport report;
};

/// Linearize the model at the operating pose (at rest, holding gravity), augment with integrators,
/// ZOH-discretize at the model's servo period, augment with `command_delay` commands in flight
/// (0..kMaxCommandDelay; 0: the undelayed design), solve the DARE, split the gain; then design the
/// steady-state Kalman observer on the same discretized plant (a second DARE; it is fed the command
/// that reaches the plant under that delay). Throws Error (e.g. unreachable pose, failed DARE).
/// Set-up code.
LqrWallDesign designLqrWall(const TauModel& model, const Vec6& operating_pose, const LqrWallWeights& weights = {},
                            const ObserverNoise& noise = {}, int command_delay = 0);
/// The same with an explicit delay model (fixed or i.i.d. random, with an input-rate weight).
LqrWallDesign designLqrWall(const TauModel& model, const Vec6& operating_pose, const LqrWallWeights& weights,
                            const ObserverNoise& noise, const CommandDelayDesign& delay);

/// Gain-only redesign at a new operating pose (e.g. each new contact point), fast enough for one
/// servo period: linearize + augment + ZOH + DARE + gain, for the delay model `designed` was made
/// for; the observer is copied from `designed`.
/// Why the observer need not follow: it only predicts one period ahead, its disturbance state d
/// absorbs the model mismatch between operating points, and its gain is set by the encoder noise,
/// not by the contact point (tests/tau: the centre's observer stays stable on the plant linearized
/// at the wall corners). Throws Error like designLqrWall.
LqrWallDesign redesignLqrWallGains(const TauModel& model, const Vec6& operating_pose, const LqrWallDesign& designed,
                                   const LqrWallWeights& weights = {});

}  // namespace uhaptics
