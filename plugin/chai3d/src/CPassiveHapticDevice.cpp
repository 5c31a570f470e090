#include "uhaptics/chai3d/CPassiveHapticDevice.hpp"

#include <cmath>
#include <cstdint>
#include <string>
#include <utility>

#include "uhaptics/chai3d/vector_conversions.hpp"
#include "uhaptics/core/fault.hpp"

namespace chai3d {
namespace {

uhaptics::PassivityControllerOptions<3> controllerOptions(double a_maxDamping, double a_guard, bool a_enabled) {
  uhaptics::PassivityControllerOptions<3> options;
  options.enabled = a_enabled;
  options.max_damping = a_maxDamping;
  options.min_rate = a_guard;
  return options;
}

void requireNonNegative(double a_value, const char* a_what) {
  if (!std::isfinite(a_value) || a_value < 0.0) {
    throw uhaptics::Error(std::string("cPassiveHapticDevice: ") + a_what + " must be finite and >= 0");
  }
}

uhaptics::Mat3 toEigen(const cMatrix3d& a_m) {
  uhaptics::Mat3 m;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) m(i, j) = a_m(i, j);
  return m;
}

// A specification's damping: a non-finite or negative statement counts as none.
double statedDamping(double a_damping) { return std::isfinite(a_damping) && a_damping > 0.0 ? a_damping : 0.0; }

}  // namespace

cPassiveHapticDevice::cPassiveHapticDevice(cGenericHapticDevicePtr a_device)
    : cGenericHapticDevice(0),
      m_device(std::move(a_device)),
      m_linear(controllerOptions(0.0, C_DEFAULT_LINEAR_GUARD, true)),
      m_angular(controllerOptions(0.0, C_DEFAULT_ANGULAR_GUARD, true)) {
  if (!m_device) throw uhaptics::Error("cPassiveHapticDevice: no device to wrap");
  m_specifications = m_device->getSpecifications();
  m_deviceAvailable = m_device->isDeviceAvailable();
  m_deviceReady = m_device->isDeviceReady();
  m_samplePosition.zero();
  m_sampleRotation.identity();
  m_maxLinearDamping = statedDamping(m_specifications.m_maxLinearDamping);
  m_maxAngularDamping = statedDamping(m_specifications.m_maxAngularDamping);
  rebuildControllers();
}

void cPassiveHapticDevice::rebuildControllers() {
  const bool enabled = m_linear.enabled();
  m_linear = uhaptics::PassivityController<3>(controllerOptions(m_maxLinearDamping, m_linearGuard, enabled));
  m_angular = uhaptics::PassivityController<3>(controllerOptions(m_maxAngularDamping, m_angularGuard, enabled));
  m_activeCount = m_faultCount = 0;
  m_commanded = false;
  m_positionFresh = m_rotationFresh = false;
}

void cPassiveHapticDevice::resetObservation() { rebuildControllers(); }

void cPassiveHapticDevice::setPassivityEnabled(bool a_enabled) {
  m_linear.setEnabled(a_enabled);
  m_angular.setEnabled(a_enabled);
}

void cPassiveHapticDevice::setMaxDamping(double a_linearDamping, double a_angularDamping) {
  requireNonNegative(a_linearDamping, "the linear damping cap [N s/m]");
  requireNonNegative(a_angularDamping, "the angular damping cap [N m s/rad]");
  m_maxLinearDamping = a_linearDamping;
  m_maxAngularDamping = a_angularDamping;
  m_dampingSet = true;
  rebuildControllers();
}

void cPassiveHapticDevice::setVelocityGuard(double a_linearRate, double a_angularRate) {
  requireNonNegative(a_linearRate, "the linear velocity guard [m/s]");
  requireNonNegative(a_angularRate, "the angular velocity guard [rad/s]");
  m_linearGuard = a_linearRate;
  m_angularGuard = a_angularRate;
  rebuildControllers();
}

void cPassiveHapticDevice::setServoPeriod(double a_period) {
  requireNonNegative(a_period, "the servo period [s]");
  m_fixedPeriod = a_period;
}

bool cPassiveHapticDevice::open() {
  const bool result = m_device->open();
  // Some device classes fill in their specification only once they know which device they found.
  m_specifications = m_device->getSpecifications();
  m_deviceAvailable = m_device->isDeviceAvailable();
  m_deviceReady = m_device->isDeviceReady();
  if (!m_dampingSet) {
    m_maxLinearDamping = statedDamping(m_specifications.m_maxLinearDamping);
    m_maxAngularDamping = statedDamping(m_specifications.m_maxAngularDamping);
  }
  rebuildControllers();
  return result;
}

bool cPassiveHapticDevice::close() {
  const bool result = m_device->close();
  m_deviceReady = m_device->isDeviceReady();
  m_commanded = false;
  return result;
}

bool cPassiveHapticDevice::calibrate(bool a_forceCalibration) { return m_device->calibrate(a_forceCalibration); }

bool cPassiveHapticDevice::getPosition(cVector3d& a_position) {
  const bool result = m_device->getPosition(a_position);
  m_samplePosition = a_position;
  m_positionFresh = true;
  return result;
}

bool cPassiveHapticDevice::getLinearVelocity(cVector3d& a_linearVelocity) {
  return m_device->getLinearVelocity(a_linearVelocity);
}

bool cPassiveHapticDevice::getRotation(cMatrix3d& a_rotation) {
  const bool result = m_device->getRotation(a_rotation);
  m_sampleRotation = a_rotation;
  m_rotationFresh = true;
  return result;
}

bool cPassiveHapticDevice::getJointAnglesRad(double a_jointAnglesRad[C_MAX_DOF]) {
  return m_device->getJointAnglesRad(a_jointAnglesRad);
}

bool cPassiveHapticDevice::getAngularVelocity(cVector3d& a_angularVelocity) {
  return m_device->getAngularVelocity(a_angularVelocity);
}

bool cPassiveHapticDevice::getTransform(cTransform& a_transform) {
  const bool result = m_device->getTransform(a_transform);
  m_samplePosition = a_transform.getLocalPos();
  m_sampleRotation = a_transform.getLocalRot();
  m_positionFresh = m_rotationFresh = true;
  return result;
}

bool cPassiveHapticDevice::getGripperAngleRad(double& a_angle) { return m_device->getGripperAngleRad(a_angle); }

bool cPassiveHapticDevice::getGripperAngularVelocity(double& a_gripperAngularVelocity) {
  return m_device->getGripperAngularVelocity(a_gripperAngularVelocity);
}

bool cPassiveHapticDevice::getForce(cVector3d& a_force) { return m_device->getForce(a_force); }

bool cPassiveHapticDevice::getTorque(cVector3d& a_torque) { return m_device->getTorque(a_torque); }

bool cPassiveHapticDevice::getGripperForce(double& a_gripperForce) { return m_device->getGripperForce(a_gripperForce); }

bool cPassiveHapticDevice::getUserSwitch(int a_switchIndex, bool& a_status) {
  return m_device->getUserSwitch(a_switchIndex, a_status);
}

bool cPassiveHapticDevice::getUserSwitches(unsigned int& a_userSwitches) {
  return m_device->getUserSwitches(a_userSwitches);
}

void cPassiveHapticDevice::setEnableGripperUserSwitch(const bool a_status) {
  m_device->setEnableGripperUserSwitch(a_status);
}

bool cPassiveHapticDevice::getEnableGripperUserSwitch() const { return m_device->getEnableGripperUserSwitch(); }

bool cPassiveHapticDevice::enableForces(bool a_value) { return m_device->enableForces(a_value); }

bool cPassiveHapticDevice::sampleDevice() {
  bool result = true;
  if (!m_positionFresh) result = m_device->getPosition(m_samplePosition) && result;
  if (m_specifications.m_sensedRotation && !m_rotationFresh) result = m_device->getRotation(m_sampleRotation) && result;
  m_positionFresh = m_rotationFresh = false;
  return result;
}

double cPassiveHapticDevice::commandPeriod() {
  if (m_fixedPeriod > 0.0) return m_fixedPeriod;
  const auto now = std::chrono::steady_clock::now();
  const double measured = m_commanded ? std::chrono::duration<double>(now - m_lastCommandTime).count() : 0.0;
  m_lastCommandTime = now;
  // Two commands within one clock tick: no period to divide by yet; CHAI3D's nominal rate instead.
  return measured > 0.0 ? measured : C_NOMINAL_PERIOD;
}

bool cPassiveHapticDevice::setForceAndTorqueAndGripperForce(const cVector3d& a_force, const cVector3d& a_torque,
                                                            double a_gripperForce) {
  const double period = commandPeriod();
  sampleDevice();
  const uhaptics::Vec3 position = toEigen(m_samplePosition);
  const bool rotation = m_specifications.m_sensedRotation;

  // Velocities: the device's own estimate when it gives one, else the difference over the period.
  cVector3d reported(0.0, 0.0, 0.0);
  uhaptics::Vec3 velocity = uhaptics::Vec3::Zero();
  if (m_commanded) {
    const uhaptics::Vec3 moved = position - m_lastPosition;
    const bool given =
        m_device->getLinearVelocity(reported) && !(reported.equals(cVector3d(0, 0, 0)) && !moved.isZero());
    velocity = given ? toEigen(reported) : uhaptics::Vec3(moved / period);
  }
  m_lastPosition = position;

  uhaptics::Vec3 angularVelocity = uhaptics::Vec3::Zero();
  if (rotation) {
    const uhaptics::Mat3 r = toEigen(m_sampleRotation);
    uhaptics::Vec3 turned = uhaptics::Vec3::Zero();
    if (m_commanded) {
      // The rotation since the last command, as a rotation vector in the device frame (small per
      // period, so its skew part is the angle; a non-finite rotation stays non-finite).
      const uhaptics::Mat3 d = r * m_lastRotation.transpose();
      const uhaptics::Vec3 axis = 0.5 * uhaptics::Vec3(d(2, 1) - d(1, 2), d(0, 2) - d(2, 0), d(1, 0) - d(0, 1));
      const double s = axis.norm();
      const double c = 0.5 * (d.trace() - 1.0);
      turned = s > 1e-12 ? uhaptics::Vec3(axis * (std::atan2(s, c) / s)) : axis;
      const bool given =
          m_device->getAngularVelocity(reported) && !(reported.equals(cVector3d(0, 0, 0)) && !turned.isZero());
      angularVelocity = given ? toEigen(reported) : uhaptics::Vec3(turned / period);
    }
    m_angle += turned;
    m_lastRotation = r;
  }
  m_commanded = true;

  uhaptics::Vec3 force, torque = toEigen(a_torque);
  const std::uint64_t activeBefore = m_linear.activeTicks() + m_angular.activeTicks();
  uhaptics::Fault fault = m_linear.update(position, velocity, toEigen(a_force), period, force);
  if (rotation) {
    const uhaptics::Fault angular = m_angular.update(m_angle, angularVelocity, toEigen(a_torque), period, torque);
    if (fault == uhaptics::Fault::kNone) fault = angular;
  } else if (!torque.allFinite()) {
    fault = uhaptics::Fault::kNonFiniteInput;
  }
  if (!m_angle.allFinite()) m_angle.setZero();  // a non-finite rotation restarts the angle (its observer restarts too)
  if (fault != uhaptics::Fault::kNone) {
    // Nothing non-finite reaches the device, nor half a command. Zero does no work: neither
    // observer counts the coming period.
    force.setZero();
    torque.setZero();
    m_linear.interrupt();
    m_angular.interrupt();
    ++m_faultCount;
  }
  if (m_linear.activeTicks() + m_angular.activeTicks() != activeBefore) ++m_activeCount;

  m_prevForce = toChai(force);
  m_prevTorque = toChai(torque);
  m_prevGripperForce = a_gripperForce;
  const bool sent = m_device->setForceAndTorqueAndGripperForce(m_prevForce, m_prevTorque, a_gripperForce);
  return sent && fault == uhaptics::Fault::kNone;
}

}  // namespace chai3d
