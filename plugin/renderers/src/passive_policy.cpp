#include "uhaptics/renderers/passive_policy.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

#include "uhaptics/core/fault.hpp"

namespace uhaptics {

PassivePolicy::Controller PassivePolicy::makeController(const Options& options) {
  if (options.actuators < 1 || options.actuators > kMaxSensedJoints)
    throw Error("PassivePolicy: actuators = " + std::to_string(options.actuators) + ", accepted 1.." +
                std::to_string(kMaxSensedJoints));
  return Controller(options.controller, options.actuators);
}

PassivePolicy::PassivePolicy(std::unique_ptr<DevicePolicy> wrapped, const Options& options, FigureRecorder& figures)
    : wrapped_(std::move(wrapped)), options_(options), controller_(makeController(options)), figures_(figures) {
  if (!wrapped_) throw Error("PassivePolicy: no policy to wrap");
  fig_energy_ = figures_.declareFigure("passivity_energy_out_mJ", FigureKind::kValue);
  fig_generated_ = figures_.declareFigure("passivity_generated_mJ", FigureKind::kValue);
  fig_peak_excess_ = figures_.declareFigure("passivity_peak_excess_mJ", FigureKind::kMaximum);
  fig_dissipated_ = figures_.declareFigure("passivity_dissipated_mJ", FigureKind::kValue);
  fig_active_ = figures_.declareFigure("passivity_active_ticks", FigureKind::kCount);
  fig_max_damping_ = figures_.declareFigure("passivity_max_damping", FigureKind::kMaximum);
  fig_faults_ = figures_.declareFigure("passivity_faults", FigureKind::kCount);
  configure(options);
}

void PassivePolicy::configure(const Options& options) {
  controller_ = makeController(options);
  options_ = options;
  const Eigen::Index n = options.actuators;
  q_.setZero(n);
  efforts_.setZero(n);
  scene_.setZero(n);
  command_.setZero(n);
  sensed_ = false;
}

std::string PassivePolicy::name() const { return wrapped_->name() + " + passivity"; }

void PassivePolicy::reset(int command_delay) {
  wrapped_->reset(command_delay);
  if (command_delay != options_.controller.command_delay) {
    Options options = options_;
    options.controller.command_delay = command_delay;  // throws beyond kScenePortMaxDelay
    controller_ = makeController(options);
    options_ = options;
  }
  controller_.reset();
  sensed_ = false;
}

void PassivePolicy::sense(const SensedJoints& reading, SensedState& state) noexcept {
  wrapped_->sense(reading, state);
  // The previous reading got no render(): the caller commanded that period, not this layer.
  if (sensed_ || reading.first) controller_.interrupt();
  q_ = Eigen::Map<const Eigen::VectorXd>(reading.positions, options_.actuators);
  sensed_ = true;
}

Fault PassivePolicy::render(const SceneInput& input, double* efforts) noexcept {
  const Fault wrapped_fault = wrapped_->render(input, efforts);
  if (!sensed_) controller_.interrupt();  // a second render() of one reading: its period is unknown
  sensed_ = false;
  const Eigen::Index n = options_.actuators;
  const std::uint64_t active_before = controller_.activeTicks();
  if (wrapped_fault != Fault::kNone) {
    // The caller sends zero for this period, a command this layer did not shape.
    controller_.interrupt();
    std::fill(efforts, efforts + n, 0.0);
    recordFigures(active_before, Fault::kNone);
    return wrapped_fault;
  }
  efforts_ = Eigen::Map<const Eigen::VectorXd>(efforts, n);
  std::fill(scene_.data(), scene_.data() + n, 0.0);
  wrapped_->ownEfforts(scene_.data());
  scene_ = efforts_ - scene_;
  const Fault fault = controller_.update(q_, efforts_, scene_, input.dt, command_);
  std::copy(command_.data(), command_.data() + n, efforts);  // zero when the controller refused
  recordFigures(active_before, fault);
  return fault;
}

void PassivePolicy::readingLost() noexcept {
  wrapped_->readingLost();
  controller_.interrupt();
  sensed_ = false;
}

void PassivePolicy::endSession() noexcept {
  wrapped_->endSession();
  controller_.interrupt();
  sensed_ = false;
}

void PassivePolicy::recordFigures(std::uint64_t active_before, Fault fault) noexcept {
  figures_.setValue(fig_energy_, 1e3 * controller_.bookedWork());
  figures_.setValue(fig_generated_, 1e3 * controller_.generated());
  figures_.observeMaximum(fig_peak_excess_, 1e3 * controller_.peakExcess());
  figures_.setValue(fig_dissipated_, 1e3 * controller_.dissipated());
  if (controller_.activeTicks() != active_before) {
    figures_.count(fig_active_);
    figures_.observeMaximum(fig_max_damping_, controller_.lastDamping());
  }
  if (fault != Fault::kNone) figures_.count(fig_faults_);
}

PassivePolicy::Options passivePolicyOptions(DevicePolicy& policy, const double* rest_joints, int joints, int actuators,
                                            const ScenePortPassivityOptions& board) {
  if (joints < 1 || joints > kMaxSensedJoints || actuators < 1 || actuators > joints)
    throw Error("passivePolicyOptions: " + std::to_string(actuators) + " actuators of " + std::to_string(joints) +
                " joints, accepted 1..joints of 1.." + std::to_string(kMaxSensedJoints));
  PassivePolicy::Options options;
  options.actuators = actuators;
  options.controller = board;
  const std::array<double, kMaxSensedJoints> rates{};
  SensedState state;
  policy.sense(SensedJoints{rest_joints, rates.data(), true}, state);
  std::array<double, kMaxSensedJoints * kMaxSensedJoints> inertia{};
  if (policy.actuatedInertia(inertia.data())) {
    const Eigen::Map<const Eigen::MatrixXd> M(inertia.data(), actuators, actuators);
    options.controller.inertia = 0.5 * (M + M.transpose());
  } else {
    options.controller.inertia.resize(0, 0);
  }
  return options;
}

}  // namespace uhaptics
