#include "uhaptics/backends/exo_finger_plant.hpp"

#include <cmath>

#include "uhaptics/core/fault.hpp"

namespace uhaptics {

ExoFingerBoardPlant::ExoFingerBoardPlant(ExoFingerModel model, const Options& options)
    : model_(std::make_unique<const ExoFingerModel>(std::move(model))),
      sim_(*model_,
           FingerTrajectory::synthesized(*model_, options.duration_s, options.flexion_period_s,
                                         options.trajectory_rate_hz),
           ExoFingerSimOptions{options.sample_rate_hz, true}),
      clock_(1.0 / options.sample_rate_hz) {}

ExoFingerBoardPlant::ExoFingerBoardPlant(std::unique_ptr<const ExoFingerModel> model, FingerTrajectory trajectory,
                                         const ExoFingerSimOptions& sim)
    : model_(std::move(model)), sim_(*model_, std::move(trajectory), sim), clock_(1.0 / sim.update_rate_hz) {}

void ExoFingerBoardPlant::readJoints(double* positions) noexcept {
  const ExoFingerState& s = sim_.state();
  positions[0] = s.q(0);
  positions[1] = s.q(1);
}

void ExoFingerBoardPlant::applyCommand(const double* efforts) noexcept {
  sim_.command(ExoFingerModel::ActuatorVector::Constant(efforts[0]));
}

void ExoFingerBoardPlant::advance(double dt) noexcept {
  const double before = sim_.state().q(0);
  long steps = 0;
  for (long n = clock_.take(dt); n > 0; --n, ++steps) sim_.step();
  if (steps > 0) lx_rate_ = (sim_.state().q(0) - before) / (static_cast<double>(steps) * clock_.period());
}

bool ExoFingerBoardPlant::readTruth(PlantTruth& truth) noexcept {
  const ExoFingerState& s = sim_.state();
  const double force = s.force(0);
  truth.position = Vec3(s.q(0), 0.0, 0.0);
  truth.velocity = Vec3(lx_rate_, 0.0, 0.0);
  truth.applied_force = Vec3(force, 0.0, 0.0);
  truth.user_force = -truth.applied_force;
  truth.saturated = std::abs(force) >= (1.0 - 1e-9) * model_->effortLimits()(0);
  return true;
}

}  // namespace uhaptics
