#include "uhaptics/chai3d/CPlanarLinkageDevice.hpp"

#include <cmath>

#include "uhaptics/backends/planar_linkage_plant.hpp"
#include "uhaptics/core/decompositions.hpp"

namespace chai3d {
namespace {

// The controller's options from the selection ("options/<device>/<name>" in the config file, or set
// in code); the controller's defaults are paper 003's. Ranges here only catch typos; the controller
// checks consistency (eps1 <= eps2) and the device constructor reports it.
template <int N>
uhaptics::FmeControllerOptions<2> optionsFrom(const uhaptics::DeviceSelection& s) {
  uhaptics::FmeControllerOptions<2> o = uhaptics::PlanarFmePolicy<N>::defaultOptions();
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
  o.max_null_space_torque = s.option("max_null_space_torque", o.max_null_space_torque, 0.01, 10.0);
  o.null_space_ramp_time = s.option("null_space_ramp_time", o.null_space_ramp_time, 0.0, 10.0);
  o.stiff_direction_time = s.option("stiff_direction_time", o.stiff_direction_time, 0.0, 1.0);
  // The null-space torque's energy tank, in mJ and mW (0 capacity: no tank).
  const double tank = s.option("null_space_tank", std::isfinite(o.null_space_tank_capacity) ? 1e3 * o.null_space_tank_capacity : 0.0,
                               0.0, 1e5);
  o.null_space_tank_capacity = tank > 0.0 ? 1e-3 * tank : std::numeric_limits<double>::infinity();
  o.null_space_tank_refill = 1e-3 * s.option("null_space_tank_refill", 1e3 * o.null_space_tank_refill, 0.0, 1e5);
  return o;
}

}  // namespace

template <int N>
cPlanarLinkageDevice<N>::cPlanarLinkageDevice(unsigned int a_deviceNumber, const uhaptics::DeviceSelection& a_selection,
                                              Model a_model, const std::string& a_title, double a_workspaceRadius)
    : cUhapticsDevice(a_deviceNumber, a_selection, 1e-3, Model::kJoints, Model::kJoints) {
  std::unique_ptr<Policy> policy;
  try {
    policy = std::make_unique<Policy>(std::move(a_model), optionsFrom<N>(a_selection), this->sessionStats());
  } catch (const uhaptics::Error& e) {
    throw uhaptics::Error("device " + a_selection.device + " (options/" + a_selection.device + "/...): " + e.what());
  }
  m_fme = policy.get();
  const Model& model = m_fme->model();
  const typename Model::JointVector home = model.homeJoints();
  this->setPolicy(std::move(policy), home.data());

  // The force the device can produce in every direction at home: torques tau = J^T F within the
  // ellipse sum (tau_i / T_i)^2 <= 1 allow |F| = 1 / sqrt(u^T J W^2 J^T u) along u; the minimum
  // over u (inside the actual box of limits, so conservative).
  typename Model::Jacobian J;
  model.jacobian(home, J);
  const typename Model::JointVector w = model.effortLimits().cwiseInverse();
  const uhaptics::Mat2 JWWJt = J * w.cwiseAbs2().asDiagonal() * J.transpose();
  uhaptics::Vec2 lambda;  // ascending
  if (!uhaptics::symmetricEigen(JWWJt, lambda)) throw uhaptics::Error("device " + a_selection.device + ": its Jacobian at home is not finite");
  const double lambda_max = lambda(1);

  setCommonSpecifications(a_title, false);
  m_specifications.m_maxLinearForce = 1.0 / std::sqrt(lambda_max);
  m_specifications.m_maxLinearStiffness = 1000.0;  // paper 003's stiff environment K_e
  this->setSpecifiedDamping();
  m_specifications.m_workspaceRadius = a_selection.option("workspace_radius", a_workspaceRadius, 0.01, 0.3);
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
  return std::make_unique<Plant>(m_fme->model(), options);
}

template <int N>
bool cPlanarLinkageDevice<N>::setNullSpaceOptions(const typename Controller::Options& a_options) {
  std::lock_guard<std::mutex> lock(deviceMutex());
  return m_fme->controller().setOptions(a_options) == uhaptics::Fault::kNone;
}

template <int N>
typename cPlanarLinkageDevice<N>::Controller::Options cPlanarLinkageDevice<N>::getNullSpaceOptions() {
  std::lock_guard<std::mutex> lock(deviceMutex());
  return m_fme->controller().options();
}

template <int N>
typename cPlanarLinkageDevice<N>::Controller::Status cPlanarLinkageDevice<N>::getNullSpaceStatus() {
  std::lock_guard<std::mutex> lock(deviceMutex());
  return m_fme->controller().status();
}

template <int N>
typename cPlanarLinkageDevice<N>::Model::JointVector cPlanarLinkageDevice<N>::getJointPositions() {
  std::lock_guard<std::mutex> lock(deviceMutex());
  return m_fme->joints();
}

template class cPlanarLinkageDevice<3>;
template class cPlanarLinkageDevice<4>;

}  // namespace chai3d
