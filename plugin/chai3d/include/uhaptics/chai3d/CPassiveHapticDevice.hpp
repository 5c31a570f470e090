#pragma once
// chai3d::cPassiveHapticDevice: the passivity layer as a CHAI3D device decorator. It wraps any
// cGenericHapticDevice (CHAI3D's own device classes such as cDeltaDevice or cPhantomDevice, a
// uhaptics device, an application's own) and is used in its place: every call is forwarded to the
// wrapped device, and setForceAndTorqueAndGripperForce() first runs the time-domain passivity
// observer and controller (uhaptics::PassivityController, Hannaford and Ryu 2002) in the task
// space, so the force the device renders never gives the user more energy than the user has put
// in.
//
// Each command, with x the tool's position, v its velocity and F the application's force:
//
//   E_out  += F_prev . (x - x_prev)           the work of the last command actually sent
//   F_sent  = F - alpha v                      alpha > 0 only while E_out > 0; it dissipates the
//                                              excess in one period if v holds, capped by the
//                                              device's maximum damping, nothing below the guard
//
// and likewise the torque on the tool's rotation (angle increments log(R R_prev^T)) when the device
// senses one, with its own observer. The gripper force is forwarded unchanged.
//
// Where the samples come from:
//  - position and rotation: those the application read through this decorator (getPosition(),
//    getRotation(), getTransform()) since the last command, which are what it computed the force
//    from; read from the wrapped device when it read none.
//  - velocity: the wrapped device's getLinearVelocity() / getAngularVelocity() (CHAI3D's device
//    classes estimate it over a time window); a device that gives none (it fails, or reports exactly
//    zero while its position moved) gets the difference of successive positions over the period.
//  - period: measured between successive commands on the steady clock, or fixed by
//    setServoPeriod() (a device paced by its own bus, a lock-step simulation).
//
// Damping caps: m_maxLinearDamping [N s/m] and m_maxAngularDamping [N m s/rad] of the wrapped
// device's specification (CHAI3D's "maximum recommended damping"), read when it opens, unless set by
// setMaxDamping(). A device whose specification states none gets none: the layer then only observes.
// The command is not held to m_maxLinearForce: a device that saturates it applies less work than the
// observer counts, both when a contact stores energy and when it gives it back.
//
// A non-finite force, torque, position or rotation sends zero force and torque, counts a fault
// (getFaultCount()) and returns C_ERROR. Like CHAI3D's device classes this is used from one thread
// (the haptic loop). No allocation per call.
#include <chrono>
#include <memory>
#include <utility>

#include "system/CGlobals.h"  // must precede device headers (CHAI3D's feature switches)
#include "devices/CGenericHapticDevice.h"

#include "uhaptics/core/passivity_controller.hpp"
#include "uhaptics/core/types.hpp"

namespace chai3d {

class cPassiveHapticDevice;
typedef std::shared_ptr<cPassiveHapticDevice> cPassiveHapticDevicePtr;

class cPassiveHapticDevice : public cGenericHapticDevice {
 public:
  //! Velocity guards by default: slower motion gets no damping [m/s], [rad/s].
  static constexpr double C_DEFAULT_LINEAR_GUARD = 1e-3;
  static constexpr double C_DEFAULT_ANGULAR_GUARD = 1e-2;
  //! Period assumed for a first command, before one can be measured [s] (CHAI3D's 1 kHz).
  static constexpr double C_NOMINAL_PERIOD = 1e-3;

  //! Constructor of cPassiveHapticDevice: wraps a_device (null: throws uhaptics::Error); passivity on.
  //! The specification is the wrapped device's (copied now and when it opens).
  explicit cPassiveHapticDevice(cGenericHapticDevicePtr a_device);
  //! Destructor of cPassiveHapticDevice (the wrapped device is left as it is).
  virtual ~cPassiveHapticDevice() {}
  //! Shared cPassiveHapticDevice allocator.
  static cPassiveHapticDevicePtr create(cGenericHapticDevicePtr a_device) {
    return std::make_shared<cPassiveHapticDevice>(std::move(a_device));
  }

  // ---- forwarded to the wrapped device ------------------------------------------------------
  //! Opens the wrapped device, copies its specification (the damping caps unless set) and starts a new observation.
  virtual bool open();
  //! Closes the wrapped device.
  virtual bool close();
  //! Calibrates the wrapped device.
  virtual bool calibrate(bool a_forceCalibration = false);
  //! Position [m] of the wrapped device; the next command's sample.
  virtual bool getPosition(cVector3d& a_position);
  //! Linear velocity [m/s] of the wrapped device.
  virtual bool getLinearVelocity(cVector3d& a_linearVelocity);
  //! Orientation of the wrapped device; the next command's sample.
  virtual bool getRotation(cMatrix3d& a_rotation);
  //! Joint angles [rad] of the wrapped device.
  virtual bool getJointAnglesRad(double a_jointAnglesRad[C_MAX_DOF]);
  //! Angular velocity [rad/s] of the wrapped device.
  virtual bool getAngularVelocity(cVector3d& a_angularVelocity);
  //! Position and orientation of the wrapped device; the next command's samples.
  virtual bool getTransform(cTransform& a_transform);
  //! Gripper angle [rad] of the wrapped device.
  virtual bool getGripperAngleRad(double& a_angle);
  //! Gripper angular velocity [rad/s] of the wrapped device.
  virtual bool getGripperAngularVelocity(double& a_gripperAngularVelocity);
  //! Force [N] the wrapped device reports (what it was last sent, damping included).
  virtual bool getForce(cVector3d& a_force);
  //! Torque [N m] the wrapped device reports.
  virtual bool getTorque(cVector3d& a_torque);
  //! Gripper force [N] the wrapped device reports.
  virtual bool getGripperForce(double& a_gripperForce);
  //! Status of one user switch of the wrapped device.
  virtual bool getUserSwitch(int a_switchIndex, bool& a_status);
  //! Status of all user switches of the wrapped device.
  virtual bool getUserSwitches(unsigned int& a_userSwitches);
  //! Enables or disables the wrapped device's virtual gripper switch.
  virtual void setEnableGripperUserSwitch(const bool a_status);
  //! Status of the wrapped device's virtual gripper switch.
  virtual bool getEnableGripperUserSwitch() const;
  //! Passivity controller on the force [N] and torque [N m], then both and the gripper force [N] to the wrapped device.
  virtual bool setForceAndTorqueAndGripperForce(const cVector3d& a_force, const cVector3d& a_torque,
                                                double a_gripperForce);
  //! Enables or disables the wrapped device's forces.
  virtual bool enableForces(bool a_value);

  // ---- the passivity layer ------------------------------------------------------------------
  //! The wrapped device.
  cGenericHapticDevicePtr getWrappedDevice() const { return m_device; }
  //! __false__: commands are forwarded unchanged (bit for bit); the observer still runs. Default __true__.
  void setPassivityEnabled(bool a_enabled);
  //! Whether the controller adds damping.
  bool getPassivityEnabled() const { return m_linear.enabled(); }
  //! Damping caps [N s/m], [N m s/rad], finite and >= 0 (else uhaptics::Error), instead of the specification's.
  //! Set-up: starts a new observation.
  void setMaxDamping(double a_linearDamping, double a_angularDamping);
  //! Velocity guards [m/s], [rad/s], finite and >= 0 (else uhaptics::Error). Set-up: starts a new observation.
  void setVelocityGuard(double a_linearRate, double a_angularRate);
  //! Fixed period between commands [s]; 0 (default): measured on the steady clock. Negative or NaN: uhaptics::Error.
  void setServoPeriod(double a_period);
  //! Forgets the observed energy and counters; the next command starts a new observation.
  void resetObservation();

  //! Net energy the sent commands have given the user [J] (force and torque; positive: the device gave energy).
  double getEnergyOut() const { return m_linear.energyOut() + m_angular.energyOut(); }
  //! Largest net energy the force's and the torque's observers reported [J], summed.
  double getPeakEnergyOut() const { return m_linear.peakEnergyOut() + m_angular.peakEnergyOut(); }
  //! Energy the added damping absorbed [J].
  double getDissipatedEnergy() const { return m_linear.dissipated() + m_angular.dissipated(); }
  //! Commands to which damping was added (force or torque).
  unsigned long long getActiveCount() const { return m_activeCount; }
  //! Commands refused (non-finite input): zero was sent.
  unsigned long long getFaultCount() const { return m_faultCount; }
  //! The force's observer and controller (position, N s/m).
  const uhaptics::PassivityController<3>& getLinearController() const { return m_linear; }
  //! The torque's observer and controller (rotation, N m s/rad); idle on a device that senses no rotation.
  const uhaptics::PassivityController<3>& getAngularController() const { return m_angular; }

 protected:
  //! Rebuilds both controllers from the caps and guards (a new observation).
  void rebuildControllers();
  //! Reads the samples the application did not read since the last command.
  bool sampleDevice();
  //! The period since the last command [s].
  double commandPeriod();

  //! The wrapped device.
  cGenericHapticDevicePtr m_device;
  //! The controllers on the force and on the torque.
  uhaptics::PassivityController<3> m_linear, m_angular;
  //! Damping caps, velocity guards; whether the caps were set by setMaxDamping().
  double m_maxLinearDamping = 0.0, m_maxAngularDamping = 0.0;
  double m_linearGuard = C_DEFAULT_LINEAR_GUARD, m_angularGuard = C_DEFAULT_ANGULAR_GUARD;
  bool m_dampingSet = false;
  //! Fixed period [s], 0: measured.
  double m_fixedPeriod = 0.0;
  //! Samples for the next command, and whether the application read them since the last one.
  cVector3d m_samplePosition;
  cMatrix3d m_sampleRotation;
  bool m_positionFresh = false, m_rotationFresh = false;
  //! The last command's position, rotation, accumulated angle [rad] and time; whether there was one.
  uhaptics::Vec3 m_lastPosition = uhaptics::Vec3::Zero();
  uhaptics::Mat3 m_lastRotation = uhaptics::Mat3::Identity();
  uhaptics::Vec3 m_angle = uhaptics::Vec3::Zero();
  std::chrono::steady_clock::time_point m_lastCommandTime;
  bool m_commanded = false;
  //! Counters.
  unsigned long long m_activeCount = 0, m_faultCount = 0;
};

}  // namespace chai3d
