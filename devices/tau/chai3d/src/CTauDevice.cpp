#include "uhaptics/chai3d/CTauDevice.hpp"

#include <algorithm>
#include <cmath>

#include "uhaptics/backends/board_catalog.hpp"
#include "uhaptics/backends/device_definition.hpp"
#include "uhaptics/backends/tau_plant.hpp"

namespace chai3d {
namespace {

uhaptics::TauPolicy::Options policyOptions(const uhaptics::DeviceSelection& a_selection, double a_servoPeriod,
                                           const std::string& a_paramsDirectory) {
  uhaptics::TauPolicy::Options options;
  options.classifier.stiff_threshold = a_selection.option("stiff_threshold", 3000.0, 1.0, 1e6);
  options.classifier.contact_force = a_selection.option("contact_force", 0.3, 0.01, 10.0);
  options.classifier.release_ticks =
      static_cast<int>(std::lround(a_selection.option("release_time", 0.05, 0.001, 1.0) / a_servoPeriod));
  options.wall_mode = static_cast<uhaptics::TauPolicy::WallMode>(static_cast<int>(a_selection.option("wall", 0.0, 0.0, 2.0)));
  // The rated spring walls at 1 kHz (the parameter file's stability section), per command delay.
  const uhaptics::BoardSpec spec = uhaptics::boardSpec(uhaptics::findDevice("tau"), a_paramsDirectory);
  const std::size_t rate = static_cast<std::size_t>(
      std::find_if(uhaptics::kRatedServoRatesHz.begin(), uhaptics::kRatedServoRatesHz.end(),
                   [a_servoPeriod](double hz) { return std::abs(hz * a_servoPeriod - 1.0) < 1e-9; }) -
      uhaptics::kRatedServoRatesHz.begin());
  if (rate < uhaptics::kRatedServoRatesHz.size())
    options.rated_spring = {spec.rated_stiffness[rate], spec.rated_stiffness_delayed[rate]};
  return options;
}

}  // namespace

cTauDevice::cTauDevice(unsigned int a_deviceNumber, const uhaptics::DeviceSelection& a_selection)
    : cUhapticsDevice(a_deviceNumber, a_selection, 1e-3, 6, 6),
      m_toolDamping(a_selection.option("tool_damping", 0.0, 0.0, 50.0)) {
  uhaptics::TauModel model = uhaptics::TauModel::load(paramsDirectory() + "/tau.json");
  if (std::abs(model.servoPeriod() - getServoPeriod()) > 1e-12) {
    throw uhaptics::Error("TAU parameter file: the servo period must be 1 ms (the LQR wall is designed for it)");
  }
  auto policy = std::make_unique<uhaptics::TauPolicy>(std::move(model), policyOptions(a_selection, getServoPeriod(), paramsDirectory()),
                                                      sessionStats());
  m_tau = policy.get();
  const uhaptics::TauModel& tau = m_tau->model();
  const uhaptics::Vec6 home = tau.homeJoints();
  setPolicy(std::move(policy), home.data());

  // Force the device can produce in any direction at home: tau = J^T [F; 0] within the torque
  // limits, minimized over a sphere of directions; likewise the torque.
  uhaptics::Mat6 J;
  tau.jacobian(home, J);
  double force = 1e9, torque = 1e9;
  for (int i = -2; i <= 2; ++i)
    for (int j = -2; j <= 2; ++j)
      for (int k = -2; k <= 2; ++k) {
        if (i == 0 && j == 0 && k == 0) continue;
        const uhaptics::Vec3 u = uhaptics::Vec3(i, j, k).normalized();
        uhaptics::Vec6 w = uhaptics::Vec6::Zero();
        w.head<3>() = u;
        force = std::min(force, (tau.effortLimits().array() / (J.transpose() * w).array().abs()).minCoeff());
        w.head<3>().setZero();
        w.tail<3>() = u;
        torque = std::min(torque, (tau.effortLimits().array() / (J.transpose() * w).array().abs()).minCoeff());
      }

  setCommonSpecifications("TAU-class 6-DoF parallel device", true);
  m_specifications.m_maxLinearForce = force;
  m_specifications.m_maxAngularTorque = torque;
  m_specifications.m_maxLinearStiffness = uhaptics::TauPolicy::kSpringWallStiffness;
  m_specifications.m_maxAngularStiffness = 1.0;    // assumed: mild rotational springs
  setSpecifiedDamping();
  m_specifications.m_workspaceRadius = tau.workspaceHalfSide();  // the 50 mm cube's inscribed sphere
}

cTauDevice::~cTauDevice() { close(); }

void cTauDevice::setWallMode(cWallMode a_mode) { m_tau->setWallMode(static_cast<uhaptics::TauPolicy::WallMode>(a_mode)); }
cTauDevice::cWallMode cTauDevice::getWallMode() { return static_cast<cWallMode>(m_tau->wallMode()); }
bool cTauDevice::isLqrWallEngaged() { return m_tau->lqrEngaged(); }

double cTauDevice::getLqrPenetration() {
  std::lock_guard<std::mutex> lock(deviceMutex());
  return m_tau->penetration();
}

double cTauDevice::getContactStiffness() {
  std::lock_guard<std::mutex> lock(deviceMutex());
  return m_tau->contactStiffness();
}

double cTauDevice::getSpringLimit() {
  std::lock_guard<std::mutex> lock(deviceMutex());
  return m_tau->springLimit();
}

bool cTauDevice::getContactSurface(cVector3d& a_point, cVector3d& a_normal) {
  uhaptics::Vec3 point, normal;
  {
    std::lock_guard<std::mutex> lock(deviceMutex());
    if (!m_tau->contactSurface(point, normal)) return false;
  }
  a_point.set(point.x(), point.y(), point.z());
  a_normal.set(normal.x(), normal.y(), normal.z());
  return true;
}

void cTauDevice::setContactSurface(bool a_active, const cVector3d& a_point, const cVector3d& a_normal) {
  std::lock_guard<std::mutex> lock(deviceMutex());
  m_tau->setContactSurface(a_active, uhaptics::Vec3(a_point(0), a_point(1), a_point(2)),
                           uhaptics::Vec3(a_normal(0), a_normal(1), a_normal(2)));
}

void cTauDevice::clearContactSurface() {
  std::lock_guard<std::mutex> lock(deviceMutex());
  m_tau->clearContactSurface();
}

std::unique_ptr<uhaptics::BoardPlant> cTauDevice::makeSimulatedPlant() {
  uhaptics::TauBoardPlant::Options options;
  options.hold_tool = false;  // the scripted hand's force is the user
  options.tool_damping = m_toolDamping;
  // The handle's rotational damping (the baseline device's 0.01 N m s/rad, as in tau-study): CHAI3D
  // tools command no torque and the scripted hand holds no orientation, so without it the
  // long-rod platform drifts in orientation under a push until a leg leaves its range.
  options.tool_rotational_damping = m_selection.option("tool_rotational_damping", 0.01, 0.0, 1.0);
  return std::make_unique<uhaptics::TauBoardPlant>(m_tau->model(), options);
}

}  // namespace chai3d
