#include "uhaptics/backends/tau_plant.hpp"

#include "uhaptics/core/fault.hpp"

namespace uhaptics {

namespace {
SimulatedTauOptions tauOptions(const TauBoardPlant::Options& o) {
  SimulatedTauOptions s;
  s.hand = o.hand;
  s.quantize = o.quantize;
  s.end_stops = o.end_stops;
  s.tool_damping = o.tool_damping;
  s.tool_rotational_damping = o.tool_rotational_damping;
  s.period = o.step_period;
  return s;
}
}  // namespace

TauBoardPlant::TauBoardPlant(TauModel model, const Options& options)
    : model_(std::make_unique<const TauModel>(std::move(model))),
      sim_(*model_, tauOptions(options)),
      clock_(sim_.period()) {
  sim_.reset(model_->homeJoints());
  if (options.hold_tool) {
    sim_.setHand(model_->homePose().head<3>(), Vec3::Zero(), Vec3::Zero());
  } else {
    sim_.detachHand();
  }
}

bool TauBoardPlant::readTruth(PlantTruth& truth) noexcept {
  truth.position = sim_.pose().head<3>();
  truth.velocity = sim_.toolVelocity();
  truth.user_force = sim_.handForce() + user_force_;
  truth.applied_force = sim_.toolForce();
  truth.saturated = (sim_.appliedTorque().cwiseAbs().array() >= (1.0 - 1e-9) * model_->effortLimits().array()).any();
  return true;
}

void TauBoardPlant::advance(double dt) noexcept {
  fault_ = Fault::kNone;
  for (long n = clock_.take(dt); n > 0; --n) {
    const Fault f = sim_.step(command_, user_force_);
    if (f != Fault::kNone) {
      fault_ = f;
      ++faults_;
    }
  }
}

}  // namespace uhaptics
