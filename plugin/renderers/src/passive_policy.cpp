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
  fig_peak_ = figures_.declareFigure("passivity_peak_energy_out_mJ", FigureKind::kMaximum);
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
  rates_.setZero(n);
  efforts_.setZero(n);
  command_.setZero(n);
  sensed_ = false;
}

std::string PassivePolicy::name() const { return wrapped_->name() + " + passivity"; }

void PassivePolicy::reset(int command_delay) {
  wrapped_->reset(command_delay);
  controller_.reset();
  sensed_ = false;
}

void PassivePolicy::sense(const SensedJoints& reading, SensedState& state) noexcept {
  wrapped_->sense(reading, state);
  // The previous reading got no render(): the caller commanded that period, not this layer.
  if (sensed_ || reading.first) controller_.interrupt();
  const Eigen::Index n = options_.actuators;
  q_ = Eigen::Map<const Eigen::VectorXd>(reading.positions, n);
  rates_ = Eigen::Map<const Eigen::VectorXd>(reading.rates, n);
  sensed_ = true;
}

Fault PassivePolicy::render(const SceneInput& input, double* efforts) noexcept {
  const Fault wrapped_fault = wrapped_->render(input, efforts);
  if (!sensed_) controller_.interrupt();  // a second render() of one reading: its period is unknown
  sensed_ = false;
  const Eigen::Index n = options_.actuators;
  const std::uint64_t active_before = controller_.activeTicks();
  if (wrapped_fault != Fault::kNone) {
    // The caller sends zero for this period: observe a zero command, which no damping may change.
    efforts_.setZero(n);
    const Fault observed = controller_.update(q_, efforts_, efforts_, input.dt, command_);
    std::fill(efforts, efforts + n, 0.0);
    recordFigures(active_before, observed);
    return wrapped_fault;
  }
  efforts_ = Eigen::Map<const Eigen::VectorXd>(efforts, n);
  const Fault fault = controller_.update(q_, rates_, efforts_, input.dt, command_);
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
  figures_.setValue(fig_energy_, 1e3 * controller_.energyOut());
  figures_.observeMaximum(fig_peak_, 1e3 * controller_.peakEnergyOut());
  figures_.setValue(fig_dissipated_, 1e3 * controller_.dissipated());
  if (controller_.activeTicks() != active_before) {
    figures_.count(fig_active_);
    figures_.observeMaximum(fig_max_damping_, controller_.lastDamping().maxCoeff());
  }
  if (fault != Fault::kNone) figures_.count(fig_faults_);
}

std::vector<double> passivityDampingCaps(DevicePolicy& policy, const double* rest_joints, int joints, int actuators,
                                         double linear_damping, double angular_damping) {
  if (joints < 1 || joints > kMaxSensedJoints || actuators < 1 || actuators > joints)
    throw Error("passivityDampingCaps: " + std::to_string(actuators) + " actuators of " + std::to_string(joints) +
                " joints, accepted 1..joints of 1.." + std::to_string(kMaxSensedJoints));
  const auto stated = [](double b) { return std::isfinite(b) && b > 0.0 ? b : 0.0; };
  const double linear = stated(linear_damping), angular = stated(angular_damping);
  // The step is far above the forward kinematics' tolerance and far below the joints' ranges.
  constexpr double kStep = 1e-5;  // [rad or m]
  std::array<double, kMaxSensedJoints> q{};
  std::copy(rest_joints, rest_joints + joints, q.begin());
  const std::array<double, kMaxSensedJoints> rates{};
  SensedState plus, minus;
  std::vector<double> caps(static_cast<std::size_t>(actuators), 0.0);
  for (int i = 0; i < actuators; ++i) {
    q[i] = rest_joints[i] + kStep;
    policy.sense(SensedJoints{q.data(), rates.data(), true}, plus);
    q[i] = rest_joints[i] - kStep;
    policy.sense(SensedJoints{q.data(), rates.data(), true}, minus);
    q[i] = rest_joints[i];
    const Vec3 linear_rate = (plus.position - minus.position) / (2.0 * kStep);
    const Mat3 turn = plus.rotation * minus.rotation.transpose();  // small: its skew part is the angle
    const Vec3 angular_rate =
        0.5 * Vec3(turn(2, 1) - turn(1, 2), turn(0, 2) - turn(2, 0), turn(1, 0) - turn(0, 1)) / (2.0 * kStep);
    const double cap = linear * linear_rate.squaredNorm() + angular * angular_rate.squaredNorm();
    caps[static_cast<std::size_t>(i)] = std::isfinite(cap) ? cap : 0.0;
  }
  policy.sense(SensedJoints{rest_joints, rates.data(), true}, plus);
  return caps;
}

}  // namespace uhaptics
