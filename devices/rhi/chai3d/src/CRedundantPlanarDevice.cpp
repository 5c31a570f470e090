#include "uhaptics/chai3d/CRedundantPlanarDevice.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>

namespace chai3d {
namespace {

// The controller's options from the selection ("options/rhi/<name>" in the config file, or set in
// code); the controller's defaults are paper 003's. Ranges here only catch typos; the controller
// checks consistency (eps1 <= eps2) and the device constructor reports it.
uhaptics::FmeControllerOptions<2> optionsFrom(const uhaptics::DeviceSelection& s) {
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
  // Joint-limit barrier and approach-speed damper (assumed limits, see devices/rhi/params/rhi4.json):
  // 0 turns each off.
  o.limit_gain = s.option("limit_gain", o.limit_gain, 0.0, 100.0);
  o.limit_margin = s.option("limit_margin", o.limit_margin, 1e-3, 1.0);
  o.limit_speed = s.option("limit_speed", o.limit_speed, 0.0, 100.0);
  // The null-space torque envelope (the paper's controller has none; see the class comment).
  o.max_null_space_torque = s.option("max_null_space_torque", cRedundantPlanarDevice::kDefaultMaxNullSpaceTorque, 0.01, 10.0);
  o.null_space_ramp_time = s.option("null_space_ramp_time", cRedundantPlanarDevice::kDefaultNullSpaceRampTime, 0.0, 10.0);
  o.stiff_direction_time = s.option("stiff_direction_time", cRedundantPlanarDevice::kDefaultStiffDirectionTime, 0.0, 1.0);
  return o;
}

}  // namespace

cRedundantPlanarDevice::cRedundantPlanarDevice(unsigned int a_deviceNumber, const uhaptics::DeviceSelection& a_selection)
    : cUhapticsDevice(a_deviceNumber, a_selection, 1e-3),
      m_model(std::make_unique<Model>(Model::fromFile(paramsDirectory() + "/rhi4.json", "rhi4"))) {
  const Model& model = *m_model;
  try {
    m_controller = std::make_unique<Controller>(model, model.torqueLimits(), model.home(), optionsFrom(a_selection));
  } catch (const uhaptics::Error& e) {
    throw uhaptics::Error(std::string("device rhi (options/rhi/...): ") + e.what());
  }
  model.forward(model.home(), m_centre);
  using Kind = uhaptics::RendererFigure::Kind;
  m_figureFreeToStiff = sessionStats().declareFigure("free_to_stiff", Kind::kCount);
  m_figureStiffToFree = sessionStats().declareFigure("stiff_to_free", Kind::kCount);
  m_figureStiffTicks = sessionStats().declareFigure("stiff_ticks", Kind::kCount);
  m_figureForceScaleReduction = sessionStats().declareFigure("max_force_scale_reduction", Kind::kMaximum);
  m_figureNullSpaceTorque = sessionStats().declareFigure("max_null_space_torque_Nm", Kind::kMaximum);

  // The force the device can produce in every direction at home: torques tau = J^T F within the
  // ellipse sum (tau_i / T_i)^2 <= 1 allow |F| = 1 / sqrt(u^T J W^2 J^T u) along u; the minimum
  // over u (inside the actual box of limits, so conservative).
  Model::Jacobian J;
  model.jacobian(model.home(), J);
  const Model::JointVector w = model.torqueLimits().cwiseInverse();
  const uhaptics::Mat2 JWWJt = J * w.cwiseAbs2().asDiagonal() * J.transpose();
  const double lambda_max = Eigen::SelfAdjointEigenSolver<uhaptics::Mat2>(JWWJt, Eigen::EigenvaluesOnly).eigenvalues()(1);

  setCommonSpecifications("4-DoF planar redundant interface", false);
  m_specifications.m_maxLinearForce = 1.0 / std::sqrt(lambda_max);
  m_specifications.m_maxLinearStiffness = 1000.0;  // paper 003's stiff environment K_e
  m_specifications.m_maxLinearDamping = 5.0;       // assumed: well inside 1 kHz stability for these masses
  // Assumed: a 10 cm disc around home keeps the arm far from the 0.786 m reach boundary.
  m_specifications.m_workspaceRadius = a_selection.option("workspace_radius", 0.1, 0.01, 0.3);
  m_q = model.home();
  updateState();
}

cRedundantPlanarDevice::~cRedundantPlanarDevice() { close(); }

void cRedundantPlanarDevice::startBackend() {
  m_controller->reset();  // free-motion ellipsoid; the null-space torque ramps up from zero
  m_stiffTarget = m_controller->status().omega_target == 0.0;
  m_tau.setZero();
  m_qd.setZero();
  m_rate.reset();
  if (hasBoard()) {
    m_sim.reset();
    startBoard(Model::kJoints, Model::kJoints, m_q.data());
  } else {
    m_sim = std::make_unique<uhaptics::SimulatedPlanarLinkage<4>>(*m_model);
    m_sim->reset(m_model->home());
    m_q = m_sim->position();
  }
  updateState();
}

void cRedundantPlanarDevice::stopBackend() noexcept {
  m_tau.setZero();
  commandBoard(m_tau.data());
}

uhaptics::Fault cRedundantPlanarDevice::servoTick(const ServoInput& a_input, double& a_outputMagnitude) noexcept {
  a_outputMagnitude = 0.0;
  if (hasBoard()) {
    std::uint32_t sample_us = 0;
    if (!readBoard(m_q.data(), sample_us)) {  // zero commanded: link down or host watchdog
      m_tau.setZero();
      return uhaptics::Fault::kDeviceError;
    }
    m_rate.update(m_q.data(), Model::kJoints, sample_us, m_qd.data());
  } else {
    m_q = m_sim->position();
    m_qd = m_sim->velocity();
  }
  // A planar device: only the in-plane force is rendered (no torque, x not actuated).
  const uhaptics::Fault fault = m_controller->tick(a_input.time, m_q, m_qd, deviceToPlanar(a_input.force), m_tau);
  a_outputMagnitude = m_tau.cwiseAbs().maxCoeff();
  recordFigures(m_controller->status());
  uhaptics::Fault backend_fault = uhaptics::Fault::kNone;
  if (hasBoard()) {
    commandBoard(m_tau.data());
  } else {
    uhaptics::EndEffectorLoad hand;
    hand.bias = deviceToPlanar(a_input.handForce);  // constant over the period
    m_sim->setLoad(hand);
    backend_fault = m_sim->step(m_tau, a_input.dt);
    m_q = m_sim->position();
    m_qd = m_sim->velocity();
  }
  updateState();
  return fault != uhaptics::Fault::kNone ? fault : backend_fault;
}

void cRedundantPlanarDevice::recordFigures(const Controller::Status& a_status) noexcept {
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

void cRedundantPlanarDevice::updateState() noexcept {
  // Kinematics of the latest joint state (the simulation's own end-effector state on sim).
  uhaptics::Vec2 x;
  Model::Jacobian J;
  m_model->forward(m_q, x);
  m_model->jacobian(m_q, J);
  m_state.position = planarToDevice(x - m_centre);
  m_state.linearVelocity = planarToDevice(J * m_qd);
  m_state.joints = m_q;
}

bool cRedundantPlanarDevice::setNullSpaceOptions(const Controller::Options& a_options) {
  std::lock_guard<std::mutex> lock(deviceMutex());
  return m_controller->setOptions(a_options) == uhaptics::Fault::kNone;
}

cRedundantPlanarDevice::Controller::Options cRedundantPlanarDevice::getNullSpaceOptions() {
  std::lock_guard<std::mutex> lock(deviceMutex());
  return m_controller->options();
}

cRedundantPlanarDevice::Controller::Status cRedundantPlanarDevice::getNullSpaceStatus() {
  std::lock_guard<std::mutex> lock(deviceMutex());
  return m_controller->status();
}

cRedundantPlanarDevice::Model::JointVector cRedundantPlanarDevice::getJointPositions() {
  std::lock_guard<std::mutex> lock(deviceMutex());
  return m_q;
}

}  // namespace chai3d
