// CHAI3D's custom-device slot, implemented by uhaptics.
//
// CHAI3D declares chai3d::cMyCustomDevice (devices/CMyCustomDevice.h) and its stock
// cHapticDeviceHandler enumerates it on Linux; libchai3d.a carries a stub that reports 0 devices.
// This file defines every member of that same declaration, so linked before libchai3d.a (as an
// object file: see plugin/chai3d/CMakeLists.txt) it replaces the stub and an unchanged application
// finds the selected uhaptics device through handler->getDevice(device, 0).
//
// Layout: the handler (compiled inside libchai3d.a) allocates cMyCustomDevice with CHAI3D's own
// sizeof, so this class can gain neither data members nor virtual functions. The actual device is
// a separate cUhapticsDevice kept in a table indexed by device number (stored in the one spare
// member, m_MyVariable); the application reaches it with uhaptics::adapter::uhapticsDevice().
//
// What an application calls on the handler's device, and who answers:
// - declared by cMyCustomDevice (open, close, calibrate, getPosition, getRotation,
//   getGripperAngleRad, getUserSwitches, setForceAndTorqueAndGripperForce): forwarded; the answer
//   is the uhaptics device's.
// - inherited and answered from members by CHAI3D's base classes (getLinearVelocity,
//   getAngularVelocity, getGripperAngularVelocity, getForce, getTorque, getGripperForce,
//   getSpecifications, isDeviceAvailable, isDeviceReady; getTransform, getUserSwitch,
//   getGripperAngleDeg, setForce and setForceAndTorque call the forwarded ones): open, close, the
//   readings and the force command copy those members from the uhaptics device, so these answers
//   are the device's as of this slot device's latest such call (another handler's device, or the
//   application through uhapticsDevice(), may have changed the device since).
// - inherited with nothing to keep current: getJointAnglesRad (CHAI3D's base answers C_ERROR) and
//   enableForces (CHAI3D's base does nothing). Call them on uhapticsDevice(device).
//
// Whatever the selection, the slot offers one device: the selected one, or, when nothing or
// something invalid is selected (or the device cannot be created), an unavailable device with a
// complete specification whose model name says why. An application therefore never falls back to
// the handler's null device, whose specification CHAI3D leaves partly uninitialised (m_model).
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
  bool selectionRead = false;  // the environment was read, or a selection was given in code
  bool selected = false;       // and it names a device
  uhaptics::DeviceSelection selection;
  std::string unavailable;  // why there is no device, when !selected
  cUhapticsDevicePtr devices[C_MAX_HAPTIC_DEVICES];
  int users[C_MAX_HAPTIC_DEVICES] = {};  // live cMyCustomDevice objects bound to each device
};

// Never destroyed: an application may keep the handler's device in a global, destroyed after any
// function-local static.
Slot& slot() {
  static Slot* instance = new Slot;
  return *instance;
}

// Reads the selection once per process (until resetSlotSelection()); prints one line saying what
// the application gets.
bool readSelectionLocked(Slot& s) {
  if (s.selectionRead) return s.selected;
  s.selectionRead = true;
  s.selected = false;
  const char* device = std::getenv("UHAPTICS_DEVICE");
  const char* config = std::getenv("UHAPTICS_CONFIG");
  if ((device == nullptr || *device == '\0') && (config == nullptr || *config == '\0')) {
    s.unavailable = "no device selected: set UHAPTICS_DEVICE";
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
    s.unavailable = std::string("invalid device selection: ") + e.what();
    std::fprintf(stderr, "uhaptics: invalid device selection: %s\n", e.what());
  }
  return s.selected;
}

// Reads and writes the members CHAI3D's base classes answer from. A class derived from
// cMyCustomDevice may name its protected members (here as pointers to members); it is never
// instantiated.
class cMyCustomDeviceAccess : public cMyCustomDevice {
 public:
  static int index(const cMyCustomDevice& a_slot) { return a_slot.*(&cMyCustomDeviceAccess::m_MyVariable); }

  /// Copies what the base classes answer from members out of a_device's own answers. Allocates
  /// nothing (the haptic loop calls it).
  static void mirror(cMyCustomDevice& a_slot, cUhapticsDevice& a_device) {
    a_device.getVelocities(a_slot.*(&cMyCustomDeviceAccess::m_linearVelocity),
                           a_slot.*(&cMyCustomDeviceAccess::m_angularVelocity));
    a_device.getGripperAngularVelocity(a_slot.*(&cMyCustomDeviceAccess::m_gripperAngularVelocity));
    a_device.getForce(a_slot.*(&cMyCustomDeviceAccess::m_prevForce));
    a_device.getTorque(a_slot.*(&cMyCustomDeviceAccess::m_prevTorque));
    a_device.getGripperForce(a_slot.*(&cMyCustomDeviceAccess::m_prevGripperForce));
    a_slot.*(&cMyCustomDeviceAccess::m_deviceAvailable) = a_device.isDeviceAvailable();
    a_slot.*(&cMyCustomDeviceAccess::m_deviceReady) = a_device.isDeviceReady();
  }
};

cUhapticsDevice* target(int a_index) {
  if (a_index < 0 || a_index >= static_cast<int>(C_MAX_HAPTIC_DEVICES)) return nullptr;
  return slot().devices[a_index].get();  // stable while this slot device is bound to it
}

}  // namespace

unsigned int cMyCustomDevice::getNumDevices() {
  Slot& s = slot();
  std::lock_guard<std::mutex> lock(s.mutex);
  readSelectionLocked(s);
  return 1u;  // the selected device, or the unavailable one that says why there is none
}

cMyCustomDevice::cMyCustomDevice(unsigned int a_deviceNumber) : cGenericHapticDevice(a_deviceNumber) {
  m_MyVariable = -1;
  m_deviceNumber = static_cast<int>(a_deviceNumber);
  m_deviceAvailable = false;
  m_deviceReady = false;
  std::string unavailable;
  {
    Slot& s = slot();
    std::lock_guard<std::mutex> lock(s.mutex);
    if (a_deviceNumber >= C_MAX_HAPTIC_DEVICES) {
      unavailable = "device number " + std::to_string(a_deviceNumber) + " out of range";
    } else if (!readSelectionLocked(s)) {
      unavailable = s.unavailable;
    } else {
      cUhapticsDevicePtr& device = s.devices[a_deviceNumber];
      if (!device) {  // a second handler in the same process shares the first one's device
        try {
          device = uhaptics::adapter::createDevice(s.selection, a_deviceNumber);
        } catch (const std::exception& e) {
          unavailable = "cannot create device '" + s.selection.device + "': " + e.what();
          std::fprintf(stderr, "uhaptics: %s\n", unavailable.c_str());
        }
      }
      if (device) {
        ++s.users[a_deviceNumber];
        m_MyVariable = static_cast<int>(a_deviceNumber);
        m_specifications = device->getSpecifications();
        cMyCustomDeviceAccess::mirror(*this, *device);
      }
    }
  }
  if (m_MyVariable < 0) {
    // CHAI3D's base constructor fills every field but the model; the rest says why.
    m_specifications.m_model = C_HAPTIC_DEVICE_CUSTOM;
    m_specifications.m_manufacturerName = "uhaptics";
    m_specifications.m_modelName = "no device (uhaptics: " + unavailable + ")";
  }
}

cMyCustomDevice::~cMyCustomDevice() {
  if (m_MyVariable < 0) return;
  cUhapticsDevicePtr released;  // destroyed (closed) outside the slot's lock
  Slot& s = slot();
  std::lock_guard<std::mutex> lock(s.mutex);
  // The last slot device bound to it lets go; the device closes when nobody else holds it (an
  // application may still, through uhapticsDevice()).
  if (--s.users[m_MyVariable] == 0) released = std::move(s.devices[m_MyVariable]);
}

bool cMyCustomDevice::open() {
  cUhapticsDevice* device = target(m_MyVariable);
  if (device == nullptr) return C_ERROR;
  const bool ok = device->open();
  m_specifications = device->getSpecifications();
  cMyCustomDeviceAccess::mirror(*this, *device);
  return ok;
}

bool cMyCustomDevice::close() {
  cUhapticsDevice* device = target(m_MyVariable);
  if (device == nullptr) return C_ERROR;
  const bool ok = device->close();
  cMyCustomDeviceAccess::mirror(*this, *device);
  return ok;
}

bool cMyCustomDevice::calibrate(bool a_forceCalibration) {
  cUhapticsDevice* device = target(m_MyVariable);
  return device != nullptr && device->calibrate(a_forceCalibration);
}

bool cMyCustomDevice::getPosition(cVector3d& a_position) {
  cUhapticsDevice* device = target(m_MyVariable);
  if (device == nullptr) return cGenericHapticDevice::getPosition(a_position);
  const bool ok = device->getPosition(a_position);  // in real-time mode this may advance servo ticks
  cMyCustomDeviceAccess::mirror(*this, *device);
  return ok;
}

bool cMyCustomDevice::getRotation(cMatrix3d& a_rotation) {
  cUhapticsDevice* device = target(m_MyVariable);
  if (device == nullptr) return cGenericHapticDevice::getRotation(a_rotation);
  const bool ok = device->getRotation(a_rotation);
  cMyCustomDeviceAccess::mirror(*this, *device);
  return ok;
}

bool cMyCustomDevice::getGripperAngleRad(double& a_angle) {
  cUhapticsDevice* device = target(m_MyVariable);
  if (device == nullptr) {
    a_angle = 0.0;
    return C_ERROR;
  }
  const bool ok = device->getGripperAngleRad(a_angle);
  cMyCustomDeviceAccess::mirror(*this, *device);
  return ok;
}

bool cMyCustomDevice::getUserSwitches(unsigned int& a_userSwitches) {
  cUhapticsDevice* device = target(m_MyVariable);
  if (device == nullptr) {
    a_userSwitches = 0;
    return C_ERROR;
  }
  return device->getUserSwitches(a_userSwitches);
}

bool cMyCustomDevice::setForceAndTorqueAndGripperForce(const cVector3d& a_force, const cVector3d& a_torque,
                                                       double a_gripperForce) {
  cUhapticsDevice* device = target(m_MyVariable);
  if (device == nullptr) return C_ERROR;
  const bool ok = device->setForceAndTorqueAndGripperForce(a_force, a_torque, a_gripperForce);
  cMyCustomDeviceAccess::mirror(*this, *device);  // the force it accepted; the state after the tick
  return ok;
}

}  // namespace chai3d

namespace uhaptics::adapter {

chai3d::cUhapticsDevicePtr uhapticsDevice(const chai3d::cGenericHapticDevicePtr& a_device) {
  if (auto direct = std::dynamic_pointer_cast<chai3d::cUhapticsDevice>(a_device)) return direct;
  const auto* slotDevice = dynamic_cast<const chai3d::cMyCustomDevice*>(a_device.get());
  if (slotDevice == nullptr) return nullptr;
  const int index = chai3d::cMyCustomDeviceAccess::index(*slotDevice);
  if (index < 0) return nullptr;  // the unavailable device
  chai3d::Slot& s = chai3d::slot();
  std::lock_guard<std::mutex> lock(s.mutex);
  return s.devices[index];
}

void selectSlotDevice(const DeviceSelection& selection) {
  chai3d::cUhapticsDevicePtr device = createDevice(selection, 0);  // throws on an invalid selection
  chai3d::cUhapticsDevicePtr previous[chai3d::C_MAX_HAPTIC_DEVICES];  // released outside the lock
  chai3d::Slot& s = chai3d::slot();
  std::lock_guard<std::mutex> lock(s.mutex);
  for (unsigned int i = 0; i < chai3d::C_MAX_HAPTIC_DEVICES; ++i) {
    if (s.users[i] > 0) {
      throw Error("selectSlotDevice: a device CHAI3D's handler handed out (number " + std::to_string(i) +
                  ") is still in use; destroy the handlers and their devices first");
    }
  }
  for (unsigned int i = 0; i < chai3d::C_MAX_HAPTIC_DEVICES; ++i) previous[i] = std::move(s.devices[i]);
  s.devices[0] = std::move(device);
  s.selection = selection;
  s.selectionRead = true;
  s.selected = true;
  s.unavailable.clear();
}

void resetSlotSelection() {
  chai3d::cUhapticsDevicePtr previous[chai3d::C_MAX_HAPTIC_DEVICES];  // released outside the lock
  chai3d::Slot& s = chai3d::slot();
  std::lock_guard<std::mutex> lock(s.mutex);
  for (unsigned int i = 0; i < chai3d::C_MAX_HAPTIC_DEVICES; ++i) {
    if (s.users[i] > 0) {
      throw Error("resetSlotSelection: a device CHAI3D's handler handed out (number " + std::to_string(i) +
                  ") is still in use; destroy the handlers and their devices first");
    }
  }
  for (unsigned int i = 0; i < chai3d::C_MAX_HAPTIC_DEVICES; ++i) previous[i] = std::move(s.devices[i]);
  s.selectionRead = false;
  s.selected = false;
  s.unavailable.clear();
}

}  // namespace uhaptics::adapter
