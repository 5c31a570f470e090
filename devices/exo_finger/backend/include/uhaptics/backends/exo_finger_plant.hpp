#pragma once
// The finger exoskeleton's simulation as its board drives it: joints (l_x [m], q_B [rad]), actuator
// force on l_x [N] (ExoFingerSim). Its user: the finger follows a trajectory (position-driven, as in
// paper 000's Fig. 4): by default a synthesized flexion-extension, or one the caller gives (a CHAI3D
// session's hand path). A user force has nothing to move.
#include <memory>

#include "uhaptics/backends/device_plants.hpp"
#include "uhaptics/backends/exo_finger_sim.hpp"
#include "uhaptics/models/exo_finger_model.hpp"

namespace uhaptics {

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
  /// The finger follows `trajectory` (made for this model), stepped at sim.update_rate_hz.
  ExoFingerBoardPlant(std::unique_ptr<const ExoFingerModel> model, FingerTrajectory trajectory,
                      const ExoFingerSimOptions& sim);

  int jointCount() const noexcept override { return ExoFingerModel::kJoints; }
  int actuatorCount() const noexcept override { return ExoFingerModel::kActuated; }
  void readJoints(double* positions) noexcept override;
  void applyCommand(const double* efforts) noexcept override;
  void advance(double dt) noexcept override;
  Fault lastFault() const noexcept override { return sim_.state().fault; }
  /// The user's port is the actuator, the only joint that does work on the position-driven finger:
  /// position (l_x, 0, 0), the force it applies, and the finger's force on it, its opposite (the
  /// linkage carries no load of its own). The referee's energy is then the actuator's work on the finger.
  bool readTruth(PlantTruth& truth) noexcept override;

  const ExoFingerModel& model() const noexcept { return *model_; }
  const ExoFingerSim& sim() const noexcept { return sim_; }

 private:
  std::unique_ptr<const ExoFingerModel> model_;  // the simulation keeps a reference
  ExoFingerSim sim_;
  FixedStepClock clock_;
  double lx_rate_ = 0.0;  // [m/s] the actuator's mean rate over the last advance()
};

}  // namespace uhaptics
