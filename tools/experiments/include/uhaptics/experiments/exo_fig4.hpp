#pragma once
// The Fig. 4 protocol of paper 000, run by uhaptics-exo-fig4 and checked by the exo tests: a finger
// trajectory is played on the simulated exoskeleton, the proxy is held at x = 0, and every frame
// each renderer's actuator force, its theoretical displayed impedance d tau_a / d q_a (eq. 2, 5, 9)
// and the finite-difference impedance Delta tau_a / Delta q_a between frames are recorded.
// Impedances are normalized as in the paper: Z_q = zq, Z_x = zq / avg(|J_a|)^2 I. Also the paper's
// claims with the checks against them (reproductionTable).
#include <array>
#include <string>
#include <vector>

#include "uhaptics/backends/exo_finger_sim.hpp"
#include "uhaptics/core/subspace_proxy_solver.hpp"
#include "uhaptics/experiments/reproduction.hpp"
#include "uhaptics/models/exo_finger_model.hpp"

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

/// Paper 000's claims on Fig. 4 (eq. 2, 5, 6, 8, 9) next to what the study measured.
experiments::ReproductionTable reproductionTable(const Fig4Study& study);

}  // namespace uhaptics::exo
