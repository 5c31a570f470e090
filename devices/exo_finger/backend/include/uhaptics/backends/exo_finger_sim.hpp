#pragma once
// Simulated finger exoskeleton: the user's finger follows a trajectory of joint angles
// (synthesized flexion-extension or a recorded CSV) and the device reports what its sensors would:
// actuator length l_x and rocker angle q_B. The commanded actuator force goes through the board's
// force loop (first-order lag, the actuator's force limit) and then through the linkage onto the
// finger joints, tau_finger = J^-T S^T F (virtual work; q_B carries no torque).
//
// The device shape every exoskeleton backend shares (this one, the later USB one, the CHAI3D
// device class):  read the state, write a command, step one update period.
//
//   ExoFingerSim sim(model, trajectory, {500.0});
//   while (!sim.finished()) { const auto& s = sim.state(); sim.command(tau); sim.step(); }
//
// The finger is position-driven (an infinitely stiff user, the setting of paper 000's Fig. 4):
// forces do not deflect it, they are recorded as the torques the user feels.
#include <functional>
#include <string>
#include <vector>

#include "uhaptics/core/fault.hpp"
#include "uhaptics/models/exo_finger_model.hpp"

namespace uhaptics {

/// Finger joint angles (q_MCP, q_PIP) over time, linearly interpolated; held at the ends.
class FingerTrajectory {
 public:
  /// Flexion-extension cycles over the working range: MCP and PIP follow raised cosines with
  /// different periods (MCP period_s, PIP 2/3 of it), so l_x and q_B do not move in lock-step (the
  /// situation where the baselines lose passivity). margin keeps the angles off the range limits.
  static FingerTrajectory synthesized(const ExoFingerModel& model, double duration_s, double period_s,
                                      double sample_rate_hz, double margin = 0.05);
  /// Small oscillations around a pose (a finger pressing into and moving along a contact):
  /// MCP = centre_0 + amplitude sin(w t), PIP = centre_1 + amplitude sin(1.5 w t + 1), w = 2 pi / period.
  static FingerTrajectory synthesizedAround(const ExoFingerModel& model, const ExoFingerModel::TaskVector& centre,
                                            double amplitude, double duration_s, double period_s,
                                            double sample_rate_hz);
  /// A recorded trajectory: CSV with header "time_s,mcp_rad,pip_rad" (extra columns ignored),
  /// strictly increasing times, every pose inside the model's working range. Throws Error naming
  /// the file and line otherwise.
  static FingerTrajectory fromCsv(const ExoFingerModel& model, const std::string& path);
  /// From samples (validated like fromCsv; origin names them in errors).
  static FingerTrajectory fromSamples(const ExoFingerModel& model, std::vector<double> time_s,
                                      std::vector<ExoFingerModel::TaskVector> x, const std::string& origin);

  /// A finger whose fingertip follows a closed path (a scene's visit, e.g. a scripted hand's
  /// anchor) as closely as its joint ranges allow. fingertip_target(t) [m, hand frame] repeats
  /// every period_s; one period is sampled at sample_rate_hz, each sample the finger angles whose
  /// fingertip is nearest the target (projected Gauss-Newton in the angle box, warm-started from
  /// the previous sample, the first one from a grid), and the period is repeated for duration_s.
  static FingerTrajectory followingPath(const ExoFingerModel& model,
                                        const std::function<Vec2(double)>& fingertip_target, double period_s,
                                        double duration_s, double sample_rate_hz);

  /// Joint angles at time t (allocation-free).
  ExoFingerModel::TaskVector at(double t) const noexcept;
  double duration() const noexcept { return time_.empty() ? 0.0 : time_.back() - time_.front(); }
  double startTime() const noexcept { return time_.empty() ? 0.0 : time_.front(); }
  std::size_t samples() const noexcept { return time_.size(); }

 private:
  std::vector<double> time_;
  std::vector<ExoFingerModel::TaskVector> x_;
};

struct ExoFingerSimOptions {
  double update_rate_hz = 500.0;        // host link rate (paper: USB at 500 Hz); faster is allowed
  bool force_loop_lag = true;           // first-order lag with the model's force-loop time constant
};

/// What a backend reports each update period.
struct ExoFingerState {
  double time = 0.0;                                                      // s
  ExoFingerModel::JointVector q = ExoFingerModel::JointVector::Zero();    // (l_x [m], q_B [rad])
  ExoFingerModel::ActuatorVector force = ExoFingerModel::ActuatorVector::Zero();  // actuator force applied (sensor), N
  ExoFingerModel::TaskVector finger_torque = ExoFingerModel::TaskVector::Zero();  // on (MCP, PIP), N m
  Fault fault = Fault::kNone;  // last command rejected (non-finite) or state out of range
};

class ExoFingerSim {
 public:
  /// Throws Error for a rate outside [10 Hz, 100 kHz] or an empty trajectory.
  ExoFingerSim(const ExoFingerModel& model, FingerTrajectory trajectory, const ExoFingerSimOptions& options = {});

  const ExoFingerState& state() const noexcept { return state_; }
  /// Commanded actuator force (N). Non-finite: rejected, the force goes to zero, state().fault says so.
  /// Beyond the force limit: saturated, as the real actuator does.
  void command(const ExoFingerModel::ActuatorVector& force) noexcept;
  /// Advances one update period: the finger moves, the force loop responds.
  void step() noexcept;
  bool finished() const noexcept;
  double period() const noexcept { return period_; }
  const ExoFingerModel& model() const noexcept { return model_; }

 private:
  void sense() noexcept;
  const ExoFingerModel& model_;
  FingerTrajectory trajectory_;
  ExoFingerSimOptions options_;
  double period_;
  double commanded_ = 0.0;
  ExoFingerState state_;
  ExoFingerData data_{model_};
};

}  // namespace uhaptics
