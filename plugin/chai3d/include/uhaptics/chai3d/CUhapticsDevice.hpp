#pragma once
// chai3d::cUhapticsDevice: the part every uhaptics device shares when it is driven by CHAI3D.
//
// CHAI3D hands the device a Cartesian force/torque in the device frame (x toward the operator, y to
// the right, z up; N, N m) from whatever thread runs the application's haptic loop, at whatever
// rate that loop spins. This class turns that into fixed-period servo ticks of the device's own
// renderer (the subclass), holds the last command between ticks as hardware does, drives the
// simulated backend with a scripted hand, and keeps session statistics (optionally written to a
// file every half second and on close, so even a killed process leaves a recent record).
//
// Time: in real-time mode (default) the number of servo ticks follows the wall clock, whatever the
// application's loop rate (at most kMaxCatchUpTicks per call: a stalled loop does not trigger a burst
// of simulation). In lock-step mode every setForceAndTorqueAndGripperForce() call is exactly one
// servo tick: deterministic, for tests.
//
// Backends: "sim" (default) steps the device's simulation inside each servo tick, with the scripted
// hand as its user. "emulated" and "usb" open the device's board (uhaptics::makeJointIo) before
// startBackend(): the board's real-time servo loop (its own thread, the board's rate, wire
// protocol, watchdogs, safety stage) carries each tick's joint reading in and efforts out, and the
// emulated board simulates the device with its own user. The servo tick itself still runs when the
// application calls, at the device's period.
//
// Subclasses implement only what differs between devices: their specification (in the
// constructor), their backend and their rendering method (the three protected hooks, which keep
// m_state current). All hooks run with the device mutex held.
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "system/CGlobals.h"  // must precede device headers (CHAI3D's feature switches)
#include "devices/CGenericHapticDevice.h"

#include "uhaptics/chai3d/device_selection.hpp"
#include "uhaptics/backends/joint_io.hpp"
#include "uhaptics/backends/scripted_hand.hpp"
#include "uhaptics/chai3d/session_stats.hpp"
#include "uhaptics/core/fault.hpp"
#include "uhaptics/core/types.hpp"

namespace chai3d {

class cUhapticsDevice;
typedef std::shared_ptr<cUhapticsDevice> cUhapticsDevicePtr;

class cUhapticsDevice : public cGenericHapticDevice {
 public:
  static constexpr int kMaxCatchUpTicks = 50;

  virtual ~cUhapticsDevice();
  cUhapticsDevice(const cUhapticsDevice&) = delete;
  cUhapticsDevice& operator=(const cUhapticsDevice&) = delete;

  // ---- CHAI3D's device contract -------------------------------------------------------------
  virtual bool open();
  virtual bool close();
  virtual bool calibrate(bool a_forceCalibration = false);
  virtual bool getPosition(cVector3d& a_position);
  virtual bool getRotation(cMatrix3d& a_rotation);
  virtual bool getLinearVelocity(cVector3d& a_linearVelocity);
  virtual bool getAngularVelocity(cVector3d& a_angularVelocity);
  virtual bool getJointAnglesRad(double a_jointAnglesRad[C_MAX_DOF]);
  /// None of the uhaptics devices has a gripper: angle and angular velocity are 0.
  virtual bool getGripperAngleRad(double& a_angle);
  virtual bool getGripperAngularVelocity(double& a_gripperAngularVelocity);
  /// The simulated devices have no buttons: always 0.
  virtual bool getUserSwitches(unsigned int& a_userSwitches);
  virtual bool setForceAndTorqueAndGripperForce(const cVector3d& a_force, const cVector3d& a_torque,
                                                double a_gripperForce);
  virtual bool enableForces(bool a_value);

  // ---- uhaptics extras ----------------------------------------------------------------------
  /// Lock-step: each setForceAndTorqueAndGripperForce() call is one servo tick (deterministic).
  void setLockStep(bool a_lockStep);
  bool getLockStep() const { return m_lockStep; }
  double getServoPeriod() const { return m_servoPeriod; }
  /// Simulated time [s] = servo ticks x period.
  double getSimulationTime();
  /// Replaces the scripted hand (throws uhaptics::Error on invalid options); sim backend only.
  void setScriptedHand(const uhaptics::ScriptedHandOptions& a_options);
  void setScriptedHandEnabled(bool a_enabled);
  bool getScriptedHandEnabled() const { return m_handEnabled; }
  /// Where to write the statistics (empty: nowhere). Only while closed; used from the next open().
  void setStatsFile(const std::string& a_path);
  uhaptics::SessionStatsSnapshot getSessionStats() const;
  /// The last tick's fault (kNone when the last command went out as computed).
  uhaptics::Fault getLastFault();
  const std::string& getDeviceName() const { return m_selection.device; }
  const std::string& getBackendName() const { return m_selection.backend; }
  /// The board's servo loop (timing statistics, events) on the emulated and usb backends while
  /// open; nullptr on sim.
  uhaptics::ServoLoop* getServoLoop();
  /// Name of the rendering method now in use (may change at run time, e.g. TAU's wall).
  virtual std::string getRendererName() const = 0;

 protected:
  /// a_servoPeriod [s]: the device's control period (its board's rate).
  cUhapticsDevice(unsigned int a_deviceNumber, const uhaptics::DeviceSelection& a_selection,
                  double a_servoPeriod);

  /// Sets up and starts the backend and sets m_state; throws uhaptics::Error with a message when it
  /// cannot.
  virtual void startBackend() = 0;
  /// Leaves the device with a zero command and releases the backend. Must not throw.
  virtual void stopBackend() noexcept = 0;
  /// What one servo period gets: the application's force [N] and torque [N m] in the device frame
  /// (zero while forces are disabled) and the scripted hand's force (zero when there is none).
  struct ServoInput {
    uhaptics::Vec3 force, torque, handForce;
    double dt;    // the servo period [s]
    double time;  // servo ticks so far x dt [s]
  };
  /// One servo period: render the application's force/torque through the device's method, apply
  /// the hand's force, advance dt and update m_state. Returns the fault (zero command sent) and
  /// the largest actuator command magnitude in a_outputMagnitude.
  virtual uhaptics::Fault servoTick(const ServoInput& a_input, double& a_outputMagnitude) noexcept = 0;
  /// What the device senses, in CHAI3D's device frame with the origin at the workspace centre. The
  /// subclass keeps it current: startBackend() sets the initial state, servoTick() the new one.
  struct State {
    uhaptics::Vec3 position = uhaptics::Vec3::Zero();
    uhaptics::Mat3 rotation = uhaptics::Mat3::Identity();
    uhaptics::Vec3 linearVelocity = uhaptics::Vec3::Zero();
    uhaptics::Vec3 angularVelocity = uhaptics::Vec3::Zero();
    /// Joint angles (actuated and sensed) [rad, or m for prismatic joints]; no heap (fixed maximum).
    Eigen::Matrix<double, Eigen::Dynamic, 1, Eigen::ColMajor, C_MAX_DOF, 1> joints;
  };

  /// Fills the fields every uhaptics device shares (manufacturer, no gripper, no switches, position
  /// sensed and actuated, both hands) and whether the orientation is too; without it every angular
  /// limit is 0. The subclass then sets its forces, stiffness, damping and workspace.
  void setCommonSpecifications(const std::string& a_modelName, bool a_orientation);
  /// Planar devices (exoskeleton finger, RHI) work in the device frame's y-z plane: task x -> +y,
  /// task y -> -z; the device x axis is never sensed nor actuated.
  static uhaptics::Vec3 planarToDevice(const uhaptics::Vec2& a_task) noexcept {
    return uhaptics::Vec3(0.0, a_task.x(), -a_task.y());
  }
  static uhaptics::Vec2 deviceToPlanar(const uhaptics::Vec3& a_device) noexcept {
    return uhaptics::Vec2(a_device.y(), -a_device.z());
  }
  /// Board backends (emulated, usb): whether one is open, and its joint I/O. readBoard() gives the
  /// newest joint reading and its device-clock time; while there is none (link down, host watchdog
  /// holding zero) it commands zero and returns false. commandBoard() hands the efforts to
  /// the board's servo loop, which checks them before they leave the host.
  bool hasBoard() const noexcept { return m_board != nullptr; }
  bool readBoard(double* a_positions, std::uint32_t& a_sampleTimeUs) noexcept;
  void commandBoard(const double* a_efforts) noexcept;
  /// In startBackend(): throws uhaptics::Error unless the board has these joint and actuator counts,
  /// then waits (at most a_timeoutSeconds) for its first joint reading, written to a_positions.
  void startBoard(int a_joints, int a_actuators, double* a_positions, double a_timeoutSeconds = 2.0);
  /// Folder of the device parameter files: uhaptics::defaultParamsDirectory() (params_location.hpp).
  static std::string paramsDirectory();
  /// The session statistics, for subclasses to declare (constructor) and record (servoTick) the
  /// figures that show their rendering method at work.
  uhaptics::SessionStats& sessionStats() noexcept { return m_stats; }
  /// Held during every hook; subclass accessors that read device state take it too.
  std::mutex& deviceMutex() { return m_mutex; }

  uhaptics::DeviceSelection m_selection;
  State m_state;

 private:
  using Clock = std::chrono::steady_clock;
  void advanceLocked(bool a_oneTick) noexcept;
  void tickLocked() noexcept;
  double wallTime() const noexcept;
  void startStatsWriter();
  void stopStatsWriter() noexcept;
  void writeStats(const std::string& a_path) noexcept;

  std::mutex m_mutex;  // the application may call from its haptic and its graphics threads
  const double m_servoPeriod;
  bool m_lockStep = false;
  bool m_forcesEnabled = true;
  bool m_handEnabled;
  std::unique_ptr<uhaptics::ScriptedHand> m_hand;
  std::unique_ptr<uhaptics::JointIo> m_board;  // emulated, usb; opened in open(), closed in close()
  uhaptics::Vec3 m_commandForce = uhaptics::Vec3::Zero();
  uhaptics::Vec3 m_commandTorque = uhaptics::Vec3::Zero();
  std::uint64_t m_ticks = 0;
  Clock::time_point m_origin;
  uhaptics::Fault m_lastFault = uhaptics::Fault::kNone;
  uhaptics::SessionStats m_stats;
  std::string m_statsPath;
  std::thread m_statsWriter;
  std::mutex m_writerMutex;
  std::condition_variable m_writerWake;
  bool m_writerStop = false;
};

}  // namespace chai3d
