// CHAI3D's custom-device slot, implemented by uhaptics.
//
// CHAI3D declares chai3d::cMyCustomDevice (devices/CMyCustomDevice.h) and its stock
// cHapticDeviceHandler enumerates it on Linux; libchai3d.a carries a stub that reports 0 devices.
// This file defines every member of that same declaration, so linked before libchai3d.a (as an
// object file: see plugin/chai3d/CMakeLists.txt) it replaces the stub and an unchanged application
// finds the selected uhaptics device through handler->getDevice(device, 0).
//
// Layout: the handler (compiled inside libchai3d.a) allocates cMyCustomDevice with CHAI3D's own
// sizeof, so this class cannot gain members. The actual device is a separate cUhapticsDevice kept in
// a table indexed by device number (stored in the one spare member, m_MyVariable); every call is
// forwarded to it. getLinearVelocity/getAngularVelocity/getJointAnglesRad are not declared by
// cMyCustomDevice, so the base class answers them: the velocities are refreshed here on every
// getPosition/getRotation; joint angles are only available through cUhapticsDevice itself.
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <string>

#include "system/CGlobals.h"  // defines C_ENABLE_CUSTOM_DEVICE_SUPPORT (with -DLINUX): include first
#include "devices/CMyCustomDevice.h"
#include "devices/CHapticDeviceHandler.h"

#include "uhaptics/chai3d/device_registry.hpp"

#if !defined(C_ENABLE_CUSTOM_DEVICE_SUPPORT)
#error "CHAI3D's custom-device support is off: compile with -DLINUX (uhaptics::chai3d_sdk adds it)"
#endif

namespace chai3d {
namespace {

struct Slot {
  std::mutex mutex;
  bool selectionRead = false;
  uhaptics::DeviceSelection selection;
  bool selected = false;
  cUhapticsDevicePtr devices[C_MAX_HAPTIC_DEVICES];
};

Slot& slot() {
  static Slot instance;
  return instance;
}

// Reads the selection once per process; prints one line saying what the application gets.
bool readSelectionLocked(Slot& s) {
  if (s.selectionRead) return s.selected;
  s.selectionRead = true;
  const char* device = std::getenv("UHAPTICS_DEVICE");
  const char* config = std::getenv("UHAPTICS_CONFIG");
  if ((device == nullptr || *device == '\0') && (config == nullptr || *config == '\0')) {
    std::fprintf(stderr, "uhaptics: no device selected (set UHAPTICS_DEVICE; %s)\n",
                 uhaptics::adapter::describeDevices().c_str());
    return false;
  }
  try {
    s.selection = uhaptics::readDeviceSelection(uhaptics::adapter::deviceNames(), uhaptics::adapter::backendNames(),
                                                [](const char* name) { return std::getenv(name); });
    s.selected = true;
    std::fprintf(stderr, "uhaptics: device '%s' on the %s backend%s\n", s.selection.device.c_str(),
                 s.selection.backend.c_str(), s.selection.hand_enabled ? ", moved by the scripted hand" : "");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "uhaptics: invalid device selection: %s\n", e.what());
  }
  return s.selected;
}

// One reading and its rate, forwarded: a closed slot answers a_closed and C_ERROR. The rate goes to
// the slot's own member because cMyCustomDevice does not declare CHAI3D's rate getters (the base
// class answers them from those members).
template <class Value, class Rate>
bool forwardReading(bool a_ready, cUhapticsDevice* a_device, Value& a_value, const Value& a_closed,
                    bool (cUhapticsDevice::*a_read)(Value&), bool (cUhapticsDevice::*a_readRate)(Rate&), Rate& a_rate) {
  if (!a_ready) {
    a_value = a_closed;
    return C_ERROR;
  }
  const bool ok = (a_device->*a_read)(a_value);
  (a_device->*a_readRate)(a_rate);
  return ok;
}

cUhapticsDevice* target(int index) {
  if (index < 0 || index >= static_cast<int>(C_MAX_HAPTIC_DEVICES)) return nullptr;
  return slot().devices[index].get();
}

}  // namespace

unsigned int cMyCustomDevice::getNumDevices() {
  Slot& s = slot();
  std::lock_guard<std::mutex> lock(s.mutex);
  return readSelectionLocked(s) ? 1u : 0u;
}

cMyCustomDevice::cMyCustomDevice(unsigned int a_deviceNumber) : cGenericHapticDevice(a_deviceNumber) {
  m_MyVariable = static_cast<int>(a_deviceNumber);
  m_deviceNumber = static_cast<int>(a_deviceNumber);
  m_deviceAvailable = false;
  m_deviceReady = false;
  Slot& s = slot();
  std::lock_guard<std::mutex> lock(s.mutex);
  if (a_deviceNumber >= C_MAX_HAPTIC_DEVICES || !readSelectionLocked(s)) {
    m_MyVariable = -1;
    return;
  }
  cUhapticsDevicePtr& device = s.devices[a_deviceNumber];
  if (!device) {  // a second handler in the same process shares the first one's device
    try {
      device = uhaptics::adapter::createDevice(s.selection, a_deviceNumber);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "uhaptics: cannot create device '%s': %s\n", s.selection.device.c_str(), e.what());
      m_MyVariable = -1;
      return;
    }
  }
  m_specifications = device->getSpecifications();
  m_deviceAvailable = true;
}

cMyCustomDevice::~cMyCustomDevice() {
  if (m_deviceReady) close();
}

bool cMyCustomDevice::open() {
  cUhapticsDevice* device = target(m_MyVariable);
  m_deviceReady = device != nullptr && device->open();
  return m_deviceReady;
}

bool cMyCustomDevice::close() {
  cUhapticsDevice* device = target(m_MyVariable);
  m_deviceReady = false;
  return device != nullptr && device->close();
}

bool cMyCustomDevice::calibrate(bool a_forceCalibration) {
  cUhapticsDevice* device = target(m_MyVariable);
  return m_deviceReady && device->calibrate(a_forceCalibration);
}

bool cMyCustomDevice::getPosition(cVector3d& a_position) {
  return forwardReading(m_deviceReady, target(m_MyVariable), a_position, cVector3d(0.0, 0.0, 0.0),
                        &cUhapticsDevice::getPosition, &cUhapticsDevice::getLinearVelocity, m_linearVelocity);
}

bool cMyCustomDevice::getRotation(cMatrix3d& a_rotation) {
  return forwardReading(m_deviceReady, target(m_MyVariable), a_rotation, cIdentity3d(), &cUhapticsDevice::getRotation,
                        &cUhapticsDevice::getAngularVelocity, m_angularVelocity);
}

bool cMyCustomDevice::getGripperAngleRad(double& a_angle) {
  return forwardReading(m_deviceReady, target(m_MyVariable), a_angle, 0.0, &cUhapticsDevice::getGripperAngleRad,
                        &cUhapticsDevice::getGripperAngularVelocity, m_gripperAngularVelocity);
}

bool cMyCustomDevice::getUserSwitches(unsigned int& a_userSwitches) {
  cUhapticsDevice* device = target(m_MyVariable);
  a_userSwitches = 0;
  return m_deviceReady && device->getUserSwitches(a_userSwitches);
}

bool cMyCustomDevice::setForceAndTorqueAndGripperForce(const cVector3d& a_force, const cVector3d& a_torque,
                                                       double a_gripperForce) {
  cUhapticsDevice* device = target(m_MyVariable);
  if (!m_deviceReady) return C_ERROR;
  m_prevForce = a_force;
  m_prevTorque = a_torque;
  m_prevGripperForce = a_gripperForce;
  return device->setForceAndTorqueAndGripperForce(a_force, a_torque, a_gripperForce);
}

}  // namespace chai3d
