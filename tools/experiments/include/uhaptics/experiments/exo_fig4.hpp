#pragma once
// The Fig. 4 protocol of paper 000, run by uhaptics-exo-fig4 and checked by the exo tests: a finger
// trajectory is played on the simulated exoskeleton, the proxy is held at x = 0, and every frame
// each renderer's actuator force, its theoretical displayed impedance d tau_a / d q_a (eq. 2, 5, 9)
// and the finite-difference impedance Delta tau_a / Delta q_a between frames are recorded.
// Impedances are normalized as in the paper: Z_q = zq, Z_x = zq / avg(|J_a|)^2 I. Also the paper's
// claims with the checks against them (reproductionTable).
//
// The energy part (runFig4Energy) runs the product instead: the exoskeleton's DevicePolicy, made by
// the device's factory, on the same motion through the hardware path (the board's sensors and rate
// estimator, the command a period late, the board's force loop), with the proxy held at x = 0 by a
// scene that pulls the finger joints with Z_x (0 - x) from the sensed x; the energy it gives the
// finger is the referee's (referee.hpp), from the plant's truth at the actuator. A force sampled and
// held, and lagging, does work a field does not: along the path it acts delta late, delta = (d + 1/2) T
// (d periods of command delay, half a period of hold) plus the force loop's delay, so to first order
//   E = W + delta S,   S = -integral of (dF/dt)(dl_x/dt) dt
// where W is the work of the method's own field F(q) (zero for the subspace proxy's spring in l_x over
// a closed motion; a loop integral for the standard method, whose field is not a gradient in l_x)
// and S > 0 wherever F stiffens against the motion (for a spring K: S = K integral of v^2). The same
// path traced backward flips W and keeps S, so (E_forward - E_backward) / 2 is W and
// (E_forward + E_backward) / 2 the sampled hold's share, which delta S predicts.
#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "uhaptics/backends/device_definition.hpp"
#include "uhaptics/backends/exo_finger_sim.hpp"
#include "uhaptics/core/subspace_proxy_solver.hpp"
#include "uhaptics/experiments/reproduction.hpp"
#include "uhaptics/models/exo_finger_model.hpp"
#include "uhaptics/renderers/device_policy.hpp"

namespace uhaptics::exo {

enum Method : int { kStandard = 0, kNullSpace, kSubspaceLinearized, kSubspaceNonlinear, kMethodCount };
const char* methodName(int m);
const char* methodKey(int m);  // CSV column prefix

struct Fig4Options {
  double update_rate_hz = 500.0;  // the USB link rate of the real device
  double duration_s = 6.0;
  double period_s = 3.0;          // MCP flexion-extension period (PIP: 2/3 of it)
  double zq = 1.0;                // Z_q (paper: 1, normalized)
  // Frames whose actuator moved less than this carry no impedance information (Delta tau / ~0):
  // 1e-6 m = 1 micrometre, far below the L16's 0.25 mm backlash.
  double min_actuator_step = 1e-6;
  SubspaceSolveOptions solver{};
  std::string trajectory_csv;     // empty: synthesized flexion-extension
  // Contact variant: proxy held at `proxy` and the finger oscillating within +-contact_amplitude of
  // it (instead of the paper's proxy at 0 and full-range flexion). Ignored when trajectory_csv is set.
  bool contact = false;
  ExoFingerModel::TaskVector proxy = ExoFingerModel::TaskVector::Zero();
  double contact_amplitude = 0.17;  // rad (~10 deg)
};

struct Fig4Frame {
  double t = 0.0;
  ExoFingerModel::JointVector q = ExoFingerModel::JointVector::Zero();
  ExoFingerModel::TaskVector x = ExoFingerModel::TaskVector::Zero();
  std::array<double, kMethodCount> force{};   // tau_a (N for zq in N/m)
  std::array<double, kMethodCount> theory{};  // d tau_a / d q_a, eq. 2, 5, 9
  std::array<double, kMethodCount> fd{};      // Delta tau_a / Delta q_a (NaN: no actuator motion)
  std::array<int, kMethodCount> fault{};      // Fault as int (0 = none)
  int nonlinear_iterations = 0;
  double nonlinear_residual = 0.0;
};

struct Fig4MethodSummary {
  int frames = 0;
  int theory_passive = 0;
  int fd_frames = 0;  // frames with a defined finite-difference impedance
  int fd_passive = 0;
  int faults = 0;
  double max_abs_force = 0.0;
  double theory_min = 0.0, theory_max = 0.0;
  double fd_max = 0.0;  // largest (least passive) finite-difference impedance
  double theoryShare() const { return frames ? double(theory_passive) / frames : 0.0; }
  double fdShare() const { return fd_frames ? double(fd_passive) / fd_frames : 0.0; }
};

struct Fig4Result {
  std::vector<Fig4Frame> frames;
  std::array<Fig4MethodSummary, kMethodCount> summary{};
  double avg_abs_Ja = 0.0;  // rad/m
  double zx = 0.0;          // Z_x = zq / avg_abs_Ja^2
  double max_subspace_theory_error = 0.0;  // max |theory - (-zq)| over frames, both subspace methods
  int max_nonlinear_iterations = 0;
  double mean_nonlinear_iterations = 0.0;
  double max_nonlinear_residual = 0.0;
};

/// Runs the protocol; throws uhaptics::Error for bad options or a bad trajectory file.
Fig4Result runFig4(const ExoFingerModel& model, const Fig4Options& options);

/// The Fig. 4 protocol and its contact variant: the same renderers with the proxy held at MCP 45,
/// PIP 50 deg and the finger within +-contact_amplitude_deg of it, where the linearization of eq. 8
/// is meant to hold (the proxy is where a contact would stop the finger).
struct Fig4Study {
  Fig4Options options;
  double contact_amplitude_deg = 5.0;
  Fig4Result protocol;
  Fig4Result contact;
};
/// Runs both; throws uhaptics::Error like runFig4.
Fig4Study runFig4Study(const ExoFingerModel& model, const Fig4Options& options, double contact_amplitude_deg);

/// The Fig. 4 motion through the device's policy, judged by the referee (see the top of this file).
struct Fig4EnergyOptions {
  /// The device's DevicePolicy factory (tools/servo's makeDevicePolicy for the exoskeleton): it must
  /// make an ExoFingerPolicy. spec: its board (sensor resolution, effort limits).
  std::function<std::unique_ptr<DevicePolicy>()> make_policy;
  BoardSpec spec;
  double servo_period_s = 0.002;  // the USB exchange (paper 000: 500 Hz)
  double board_period_s = 0.001;  // the plant's step: the board samples at 1 kHz
  int command_delay = 1;          // periods between a reading and its command (ServoLoop::kCommandDelayPeriods)
  bool force_loop_lag = true;     // the board's force loop (the model's time constant)
  /// Without a trajectory file: false, the Fig. 4 motion (FingerTrajectory::synthesized: MCP and PIP
  /// raised cosines of periods P and 2P/3 from rest, whose path back retraces the path out, so it
  /// encloses no area in (l_x, q_B)); true, a loop over the same ranges: both joints at period P,
  /// the PIP a quarter cycle ahead, so the finger's angles go round an ellipse.
  bool loop = false;
  /// The reference: a servo period this short, no delay, no lag, leaves the field's own work W and
  /// a hold of delta = T / 2, a few thousandths of the product's.
  double fine_period_s = 5e-5;
};

/// The methods the policy renders (ExoFingerPolicy::Method), by this file's Method.
inline constexpr std::array<int, 3> kPolicyMethods = {kSubspaceNonlinear, kStandard, kNullSpace};

/// One run of the policy along the path.
struct Fig4EnergyRun {
  double generated_mJ = 0.0;    // the referee's generated_energy_mJ
  double stiffening_W = 0.0;    // S = -sum Delta F Delta l_x / T over the commanded force [W]
  double max_abs_force_N = 0.0; // largest |command|
  std::uint64_t faults = 0;     // periods with a fault or a non-finite command (sent as zero)
};

struct Fig4MethodEnergy {
  Fig4EnergyRun forward, backward;            // the product's rate, delay and force loop
  Fig4EnergyRun fine_forward, fine_backward;  // fine_period_s, no delay, no lag
  /// W, the field's own work along the forward path: (E_forward - E_backward) / 2 of the fine runs.
  double fieldWork_mJ() const { return 0.5 * (fine_forward.generated_mJ - fine_backward.generated_mJ); }
  /// The sampled hold's share at the product's rate, measured: (E_forward + E_backward) / 2.
  double holdShare_mJ() const { return 0.5 * (forward.generated_mJ + backward.generated_mJ); }
  /// The same share in closed form: delta S (S of the fine forward run).
  double holdClosedForm_mJ(double delta_s) const { return 1e3 * delta_s * fine_forward.stiffening_W; }
};

struct Fig4Energy {
  Fig4EnergyOptions options;
  double zx = 0.0;        // the policy's coupling stiffness, the paper's Z_x [N m/rad]
  double zq = 0.0;        // the policy's Z_q [N/m] (Z_x avg |J_a|^2 over the working range)
  double delay_s = 0.0;   // delta at the product's rate
  double closure_rad = 0.0;  // |x(end) - x(start)|: 0 for a closed motion
  std::array<Fig4MethodEnergy, kMethodCount> methods{};  // filled for kPolicyMethods
};

/// The effective delay delta [s], as the referee reads it, of a command computed at period T from a
/// reading d periods old and held: without a force loop (tau = 0) (d + 1/2) T. Through the board's
/// first-order force loop (time constant tau >> h, stepped at h), which smooths the held steps:
/// d T + h / 2 + h / (exp(h / tau) - 1), about d T + tau. That is T / 2 - h / 2 short of the force's
/// delay within the period (d T + T / 2 + the lag) because the referee holds each period's closing
/// force over the whole period, and a lagging force closes the period fresher than it acted.
double heldForceDelay(double servo_period, int command_delay, double board_period, double force_loop_tau) noexcept;

/// Runs the policy's three methods along the study's motion (synthesized as options.duration_s /
/// period_s, or options.trajectory_csv) forward and backward, with Z_x = zq / avg(|J_a|)^2 as in the
/// protocol. Throws uhaptics::Error for bad options, a trajectory like runFig4, or a factory that does
/// not make the exoskeleton's policy.
Fig4Energy runFig4Energy(const ExoFingerModel& model, const Fig4Options& options, const Fig4EnergyOptions& energy);

/// Paper 000's claims on Fig. 4 (eq. 2, 5, 6, 8, 9) next to what the study measured; with the energy
/// runs (the Fig. 4 motion, pip_phase_rad 0, and the loop, pi / 2), the referee's generated energy.
experiments::ReproductionTable reproductionTable(const Fig4Study& study, const Fig4Energy* fig4_motion = nullptr,
                                                 const Fig4Energy* loop = nullptr);

}  // namespace uhaptics::exo
