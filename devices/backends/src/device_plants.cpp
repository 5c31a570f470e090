#include "uhaptics/backends/device_plants.hpp"

#include <cmath>

#include "uhaptics/core/fault.hpp"

namespace uhaptics {

FixedStepClock::FixedStepClock(double period, double max_catch_up) : period_(period) {
  if (!(period > 0.0) || !std::isfinite(period) || !(max_catch_up >= period) || !std::isfinite(max_catch_up))
    throw Error("FixedStepClock: the period must be finite and > 0, the catch-up limit at least one period");
  max_steps_ = static_cast<long>(std::floor(max_catch_up / period));
}

long FixedStepClock::take(double dt) noexcept {
  if (!(dt > 0.0) || !std::isfinite(dt)) return 0;
  pending_ += dt;
  const double steps = std::floor(pending_ / period_);
  pending_ -= steps * period_;
  if (steps > static_cast<double>(max_steps_)) {
    dropped_ += (steps - static_cast<double>(max_steps_)) * period_;
    return max_steps_;
  }
  return static_cast<long>(steps);
}

// ---- finger exoskeleton ----------------------------------------------------------------------

ExoFingerBoardPlant::ExoFingerBoardPlant(ExoFingerModel model, const Options& options)
    : model_(std::make_unique<const ExoFingerModel>(std::move(model))),
      sim_(*model_,
           FingerTrajectory::synthesized(*model_, options.duration_s, options.flexion_period_s,
                                         options.trajectory_rate_hz),
           ExoFingerSimOptions{options.sample_rate_hz, true}),
      clock_(1.0 / options.sample_rate_hz) {}

void ExoFingerBoardPlant::readJoints(double* positions) noexcept {
  const ExoFingerState& s = sim_.state();
  positions[0] = s.q(0);
  positions[1] = s.q(1);
}

void ExoFingerBoardPlant::applyCommand(const double* efforts) noexcept {
  sim_.command(ExoFingerModel::ActuatorVector::Constant(efforts[0]));
}

void ExoFingerBoardPlant::advance(double dt) noexcept {
  for (long n = clock_.take(dt); n > 0; --n) sim_.step();
}

// ---- TAU ------------------------------------------------------------------------------------

namespace {
SimulatedTauOptions tauOptions(const TauBoardPlant::Options& o) {
  SimulatedTauOptions s;
  s.hand = o.hand;
  s.quantize = o.quantize;
  s.tool_rotational_damping = o.tool_rotational_damping;
  return s;
}
}  // namespace

TauBoardPlant::TauBoardPlant(TauModel model, const Options& options)
    : model_(std::make_unique<const TauModel>(std::move(model))),
      sim_(*model_, tauOptions(options)),
      clock_(model_->servoPeriod()) {
  sim_.reset(model_->homeJoints());
  sim_.setHand(model_->homePose().head<3>(), Vec3::Zero(), Vec3::Zero());
}

void TauBoardPlant::advance(double dt) noexcept {
  for (long n = clock_.take(dt); n > 0; --n)
    if (sim_.step(command_, Vec3::Zero()) != Fault::kNone) ++faults_;
}

// ---- RHI planar -----------------------------------------------------------------------------

RhiBoardPlant::RhiBoardPlant(Rhi4Model model, const Options& options)
    : sim_(std::move(model), options.substep), clock_(options.substep) {
  if (!(options.hand_stiffness >= 0.0) || !(options.hand_damping >= 0.0))
    throw Error("RhiBoardPlant: hand stiffness and damping must be >= 0");
  EndEffectorLoad hand;
  hand.anchor = sim_.endEffectorPosition();
  hand.stiffness = options.hand_stiffness * Mat2::Identity();
  hand.damping = options.hand_damping * Mat2::Identity();
  sim_.setLoad(hand);
}

void RhiBoardPlant::advance(double dt) noexcept {
  const long n = clock_.take(dt);
  if (n > 0) sim_.step(command_, static_cast<double>(n) * clock_.period());
}

}  // namespace uhaptics
