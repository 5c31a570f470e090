#include "uhaptics/chai3d/CPlanarLinkageDevice.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>

#include "uhaptics/backends/planar_linkage_plant.hpp"

namespace chai3d {
namespace {

// The controller's options from the selection ("options/<device>/<name>" in the config file, or set
// in code); the controller's defaults are paper 003's. Ranges here only catch typos; the controller
// checks consistency (eps1 <= eps2) and the device constructor reports it.
template <int N>
uhaptics::FmeControllerOptions<2> optionsFrom(const uhaptics::DeviceSelection& s) {
  using Device = cPlanarLinkageDevice<N>;
  uhaptics::FmeControllerOptions<2> o;
  const double mode = s.option("mode", 0.0, 0.0, 2.0);
  o.mode = mode == 1.0 ? uhaptics::FmeEllipsoidMode::kFree
                       : mode == 2.0 ? uhaptics::FmeEllipsoidMode::kStiff : uhaptics::FmeEllipsoidMode::kAuto;
  o.mu = s.option("mu", o.mu, 1e-3, 1e3);
  o.beta = s.option("beta", o.beta, 0.0, 1e4);
  o.damping = s.option("damping", o.damping, 0.0, 100.0);
  o.observer_shape = s.option("observer_shape", o.observer_shape, 1e-3, 1e4);
  o.transition.enter_stiff_below = s.option("eps1", o.transition.enter_stiff_below, 0.0, 1.0);
  o.transition.leave_stiff_at = s.option("eps2", o.transition.leave_stiff_at, 0.0, 1.0);
  o.transition.rho = s.option("rho", o.transition.rho, 0.0, 10.0);
  // Joint-limit barrier and approach-speed damper (the limits of the device's parameter file): 0 turns each off.
  o.limit_gain = s.option("limit_gain", o.limit_gain, 0.0, 100.0);
  o.limit_margin = s.option("limit_margin", o.limit_margin, 1e-3, 1.0);
  o.limit_speed = s.option("limit_speed", o.limit_speed, 0.0, 100.0);
  // The null-space torque envelope (the paper's controller has none; see the class comment).
  o.max_null_space_torque = s.option("max_null_space_torque", Device::kDefaultMaxNullSpaceTorque, 0.01, 10.0);
  o.null_space_ramp_time = s.option("null_space_ramp_time", Device::kDefaultNullSpaceRampTime, 0.0, 10.0);
  o.stiff_direction_time = s.option("stiff_direction_time", Device::kDefaultStiffDirectionTime, 0.0, 1.0);
  return o;
}

}  // namespace

template <int N>
cPlanarLinkageDevice<N>::cPlanarLinkageDevice(unsigned int a_deviceNumber, const uhaptics::DeviceSelection& a_selection,
                                              Model a_model, const std::string& a_title, double a_workspaceRadius)
    : cUhapticsDevice(a_deviceNumber, a_selection, 1e-3, Model::kJoints, Model::kJoints),
      m_model(std::make_unique<const Model>(std::move(a_model))) {
  const Model& model = *m_model;
  try {
    m_controller = std::make_unique<Controller>(model, model.effortLimits(), model.homeJoints(), optionsFrom<N>(a_selection));
  } catch (const uhaptics::Error& e) {
    throw uhaptics::Error("device " + a_selection.device + " (options/" + a_selection.device + "/...): " + e.what());
  }
  model.forward(model.homeJoints(), m_centre);
  using Kind = uhaptics::RendererFigure::Kind;
  m_figureFreeToStiff = sessionStats().declareFigure("free_to_stiff", Kind::kCount);
  m_figureStiffToFree = sessionStats().declareFigure("stiff_to_free", Kind::kCount);
  m_figureStiffTicks = sessionStats().declareFigure("stiff_ticks", Kind::kCount);
  m_figureForceScaleReduction = sessionStats().declareFigure("max_force_scale_reduction", Kind::kMaximum);
  m_figureNullSpaceTorque = sessionStats().declareFigure("max_null_space_torque_Nm", Kind::kMaximum);

  // The force the device can produce in every direction at home: torques tau = J^T F within the
  // ellipse sum (tau_i / T_i)^2 <= 1 allow |F| = 1 / sqrt(u^T J W^2 J^T u) along u; the minimum
  // over u (inside the actual box of limits, so conservative).
  typename Model::Jacobian J;
  model.jacobian(model.homeJoints(), J);
  const typename Model::JointVector w = model.effortLimits().cwiseInverse();
  const uhaptics::Mat2 JWWJt = J * w.cwiseAbs2().asDiagonal() * J.transpose();
  const double lambda_max = Eigen::SelfAdjointEigenSolver<uhaptics::Mat2>(JWWJt, Eigen::EigenvaluesOnly).eigenvalues()(1);

  setCommonSpecifications(a_title, false);
  m_specifications.m_maxLinearForce = 1.0 / std::sqrt(lambda_max);
  m_specifications.m_maxLinearStiffness = 1000.0;  // paper 003's stiff environment K_e
  m_specifications.m_maxLinearDamping = 5.0;       // assumed: well inside 1 kHz stability for these masses
  m_specifications.m_workspaceRadius = a_selection.option("workspace_radius", a_workspaceRadius, 0.01, 0.3);
  m_q = model.homeJoints();
  updateState();
}

template <int N>
cPlanarLinkageDevice<N>::~cPlanarLinkageDevice() {
  close();
}

template <int N>
std::unique_ptr<uhaptics::BoardPlant> cPlanarLinkageDevice<N>::makeSimulatedPlant() {
  using Plant = uhaptics::PlanarLinkagePlant<N>;
  typename Plant::Options options;
  options.hand_stiffness = 0.0;  // no grip: the scripted hand is the user
  options.hand_damping = 0.0;
  return std::make_unique<Plant>(*m_model, options);
}

template <int N>
void cPlanarLinkageDevice<N>::resetRendering() {
  m_controller->reset();  // free-motion ellipsoid; the null-space torque ramps up from zero
  m_stiffTarget = m_controller->status().omega_target == 0.0;
  m_tau.setZero();
}

template <int N>
void cPlanarLinkageDevice<N>::sense(const JointReading& a_reading) noexcept {
  m_q = Eigen::Map<const typename Model::JointVector>(a_reading.positions);
  m_qd = Eigen::Map<const typename Model::JointVector>(a_reading.rates);
  updateState();
}

template <int N>
uhaptics::Fault cPlanarLinkageDevice<N>::render(const ServoInput& a_input, double* a_efforts) noexcept {
  // A planar device: only the in-plane force is rendered (no torque, x not actuated).
  const uhaptics::Fault fault = m_controller->tick(a_input.time, m_q, m_qd, deviceToPlanar(a_input.force), m_tau);
  recordFigures(m_controller->status());
  Eigen::Map<typename Model::JointVector> out(a_efforts);
  out = m_tau;
  return fault;
}

template <int N>
void cPlanarLinkageDevice<N>::recordFigures(const typename Controller::Status& a_status) noexcept {
  uhaptics::SessionStats& stats = sessionStats();
  // A switch is where the desired ellipsoid starts moving towards the other one (the observer's
  // hysteresis decision, or a change of mode); a reversal mid-blend counts as a switch back.
  const bool stiff_target = a_status.omega_target == 0.0;
  if (stiff_target && !m_stiffTarget) stats.count(m_figureFreeToStiff);
  if (!stiff_target && m_stiffTarget) stats.count(m_figureStiffToFree);
  m_stiffTarget = stiff_target;
  if (a_status.omega < 1.0) stats.count(m_figureStiffTicks);  // any share of the stiff ellipsoid, blends included
  stats.observeMaximum(m_figureForceScaleReduction, 1.0 - a_status.alpha);
  stats.observeMaximum(m_figureNullSpaceTorque, a_status.tau_null.norm());
}

template <int N>
void cPlanarLinkageDevice<N>::updateState() noexcept {
  // Kinematics of the latest joint reading.
  uhaptics::Vec2 x;
  typename Model::Jacobian J;
  m_model->forwardAndJacobian(m_q, x, J);
  m_state.position = planarToDevice(x - m_centre);
  m_state.linearVelocity = planarToDevice(J * m_qd);
  m_state.joints = m_q;
}

template <int N>
bool cPlanarLinkageDevice<N>::setNullSpaceOptions(const typename Controller::Options& a_options) {
  std::lock_guard<std::mutex> lock(deviceMutex());
  return m_controller->setOptions(a_options) == uhaptics::Fault::kNone;
}

template <int N>
typename cPlanarLinkageDevice<N>::Controller::Options cPlanarLinkageDevice<N>::getNullSpaceOptions() {
  std::lock_guard<std::mutex> lock(deviceMutex());
  return m_controller->options();
}

template <int N>
typename cPlanarLinkageDevice<N>::Controller::Status cPlanarLinkageDevice<N>::getNullSpaceStatus() {
  std::lock_guard<std::mutex> lock(deviceMutex());
  return m_controller->status();
}

template <int N>
typename cPlanarLinkageDevice<N>::Model::JointVector cPlanarLinkageDevice<N>::getJointPositions() {
  std::lock_guard<std::mutex> lock(deviceMutex());
  return m_q;
}

template class cPlanarLinkageDevice<3>;
template class cPlanarLinkageDevice<4>;

}  // namespace chai3d
