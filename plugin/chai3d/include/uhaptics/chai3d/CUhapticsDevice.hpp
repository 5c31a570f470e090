#pragma once
// chai3d::cUhapticsDevice: the part every uhaptics device shares when it is driven by CHAI3D.
//
// CHAI3D hands the device a Cartesian force/torque in the device frame (x toward the operator, y to
// the right, z up; N, N m) from whatever thread runs the application's haptic loop, at whatever
// rate that loop spins. The device renders it in fixed-period servo ticks, each the same cycle on
// every backend over one joint I/O (uhaptics::JointIo):
//
//   read the joints -> sense() (kinematics, CHAI3D state) -> render() (efforts) -> command
//
// sense() and render() are the device's rendering policy (uhaptics::DevicePolicy, device_policy.hpp:
// one object per device, in the renderer layer, which the servo tool runs too); where they run
// depends on the backend:
//
//  - "emulated" and "usb" (a board: the in-process emulator or the device's controller board): in
//    the board's real-time servo thread, once per period, on that period's encoder reading (paper
//    001 ran its controller at the device's servo rate on the device's own target). The
//    application's haptic thread only publishes what the scene asks for (force, torque, the
//    position it computed them from), time-stamped, and reads back the state; both through
//    wait-free triple buffers, so neither thread waits for the other. Input older than the stale
//    time (option "stale_time", default 10 ms; no setForce() since) is a fault like a lost link:
//    the policy's readingLost() ends the contact (the TAU's LQR wall lets go), the efforts ramp linearly to zero
//    over kStaleRampPeriods periods, the statistics count it, and rendering resumes with the next
//    publication.
//  - "sim" (default): the device's simulated plant (makeSimulatedPlant()) stepped by the
//    application's calls. In real-time mode the number of ticks follows the wall clock, whatever
//    the application's loop rate (at most kMaxCatchUpTicks per call: a stalled loop does not
//    trigger a burst of simulation); in lock-step mode every setForceAndTorqueAndGripperForce()
//    call is exactly one tick (deterministic, for tests).
//
// Paced (option "pace", default on; every backend but lock-step): setForceAndTorqueAndGripperForce()
// returns when the next servo period begins, as a hardware driver returns after its device's next
// bus frame. CHAI3D's haptic loop then runs at the servo rate instead of spinning a core.
//
// On every backend the policy sees the joints as the sensors give them (the simulated encoders
// quantize like the board's) and rates from one estimator (JointRateEstimator over the device's
// sample clock): nothing the simulation knows beyond what a board reports. The scripted hand (the
// simulated user) pushes the simulated plant on "sim" and the emulated board's plant on
// "emulated", from the sensed state, each servo period.
//
// Statistics (session_stats.hpp): recorded by whichever thread ticks, optionally written to a file
// every half second and on close, so even a killed process leaves a recent record.
//
// Hand recording (DeviceSelection::record_path; docs/recording.md): the scripted hand's side of the
// session (its anchor, grip and force limit, the scene's force and the position it was computed
// from) at kHandRecordingRate into a buffer allocated when the device is made, written with the
// statistics. A full buffer keeps the first kHandRecordingSeconds and counts the rows it drops.
//
// Referee (option "referee", default 1 on sim and emulated; usb has none): the simulated plant is
// judged from its truth (uhaptics::Referee, referee.hpp): true penetration, rendered stiffness,
// rate-hardness, applied against asked force, energy given to the user, chatter, saturation. Each
// servo tick hands it the force the scene asked for; it never feeds the policy. Its figures are the
// statistics' "referee" object (docs/chai3d.md, "The referee"). 0 leaves the plant unobserved.
//
// Passivity layer (option "passivity", default 0: off): 1 wraps the device's policy in
// uhaptics::PassivePolicy (passive_policy.hpp), which observes the share of the command that
// renders the scene against the scene's continuous-time work and damps what the sampling and the
// command delay generate, in the same servo tick; 2 observes only (the energy figures, no damping).
// Off, the policy runs unwrapped and the tick does none of its work. Read here for every device;
// open() sets it up from the board it opened: the effort limits and sensor steps of its descriptor,
// the command delay, and the damping cap from the policy's joint-space inertia (option
// "passivity_max_damping" caps it further: see getPassivityDampingCaps()).
//
// Subclasses supply only what is CHAI3D's or the simulation's: their specification and their policy
// (in the constructor, setPolicy()), their simulated plant, and accessors for their policy's state.
// The policy runs with the device mutex (deviceMutex()) held, in the thread that ticks; subclass
// accessors that read its state take it too. The application's hot path (getPosition(),
// setForce...()) never takes it on a board backend.
#include <array>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "system/CGlobals.h"  // must precede device headers (CHAI3D's feature switches)
#include "devices/CGenericHapticDevice.h"

#include "uhaptics/backends/board_plant.hpp"
#include "uhaptics/backends/joint_io.hpp"
#include "uhaptics/backends/lockfree.hpp"
#include "uhaptics/chai3d/device_selection.hpp"
#include "uhaptics/backends/scripted_hand.hpp"
#include "uhaptics/chai3d/session_stats.hpp"
#include "uhaptics/core/fault.hpp"
#include "uhaptics/core/types.hpp"
#include "uhaptics/renderers/device_policy.hpp"
#include "uhaptics/renderers/passive_policy.hpp"

namespace chai3d {

class cUhapticsDevice;
typedef std::shared_ptr<cUhapticsDevice> cUhapticsDevicePtr;

class cUhapticsDevice : public cGenericHapticDevice {
 public:
  /// sim, real-time mode: the most servo ticks one application call simulates; a longer stall of
  /// the application's loop drops the rest instead of simulating it in a burst.
  static constexpr int kMaxCatchUpTicks = 50;
  /// Board backends: periods over which the efforts ramp to zero once the application's input is
  /// stale (10 ms at 1 kHz).
  static constexpr int kStaleRampPeriods = 10;
  /// Rows a second of a hand recording: the hand's anchor moves smoothly (straight segments at
  /// constant speed), so linear interpolation between rows 10 ms apart misses it only within 10 ms
  /// of a corner, and a 10 s scene is about 100 kB, small enough to ship with the tests.
  static constexpr double kHandRecordingRate = 100.0;  // [Hz]
  /// The longest hand recording kept (its buffer: about 7 MB).
  static constexpr double kHandRecordingSeconds = 600.0;  // [s]

  virtual ~cUhapticsDevice();
  cUhapticsDevice(const cUhapticsDevice&) = delete;
  cUhapticsDevice& operator=(const cUhapticsDevice&) = delete;

  // ---- CHAI3D's device contract -------------------------------------------------------------
  // The getters return C_SUCCESS (true) while the device is open and C_ERROR (false) otherwise
  // (still filling in the last state it had). Nothing here throws.
  /// Connects the selected backend, waits up to 2 s for the first joint reading and resets the
  /// rendering. C_SUCCESS when open (also when it already was); on failure it prints why to stderr,
  /// leaves nothing running or commanded and returns C_ERROR. Never throws.
  virtual bool open();
  /// Commands zero, ends the session (a board's servo thread stops) and writes the statistics
  /// file if one is set. Idempotent; C_SUCCESS.
  virtual bool close();
  /// Nothing to calibrate (positions are absolute): C_SUCCESS while open.
  virtual bool calibrate(bool a_forceCalibration = false);
  /// Position [m] in the device frame, origin at the workspace centre.
  virtual bool getPosition(cVector3d& a_position);
  /// Orientation in the device frame (identity for devices that sense none).
  virtual bool getRotation(cMatrix3d& a_rotation);
  /// [m/s] and [rad/s], device frame, from the sensed joint rates.
  virtual bool getLinearVelocity(cVector3d& a_linearVelocity);
  virtual bool getAngularVelocity(cVector3d& a_angularVelocity);
  /// Sensed joints [rad, or m for prismatic joints] in the device's joint order; 0 beyond its count.
  virtual bool getJointAnglesRad(double a_jointAnglesRad[C_MAX_DOF]);
  /// getLinearVelocity() and getAngularVelocity() in one call (one lock): CHAI3D's custom-device
  /// slot copies both after every call it forwards.
  bool getVelocities(cVector3d& a_linearVelocity, cVector3d& a_angularVelocity);
  /// None of the uhaptics devices has a gripper: angle and angular velocity are 0.
  virtual bool getGripperAngleRad(double& a_angle);
  virtual bool getGripperAngularVelocity(double& a_gripperAngularVelocity);
  /// The simulated devices have no buttons: always 0.
  virtual bool getUserSwitches(unsigned int& a_userSwitches);
  /// The force [N] and torque [N m] to render, device frame; the gripper force is ignored. A
  /// non-finite value renders zero, counts as a fault (getSessionStats()) and returns C_ERROR, as
  /// does a call while closed. On sim it also advances the simulation (see above). Paced (option
  /// "pace", default 1; not in lock-step): returns when the device's next servo period begins, at
  /// most one period later, as a hardware driver returns after the device's next bus frame.
  virtual bool setForceAndTorqueAndGripperForce(const cVector3d& a_force, const cVector3d& a_torque,
                                                double a_gripperForce);
  /// false: the servo ticks render zero force and torque until re-enabled. Always C_SUCCESS.
  virtual bool enableForces(bool a_value);

  // ---- uhaptics extras ----------------------------------------------------------------------
  /// Lock-step: each setForceAndTorqueAndGripperForce() call is one servo tick (deterministic).
  /// sim only: a board's servo thread keeps its own clock.
  void setLockStep(bool a_lockStep);
  bool getLockStep() const { return m_lockStep; }
  /// The device's control period [s].
  double getServoPeriod() const { return m_servoPeriod; }
  /// Simulated time [s] = servo ticks x period.
  double getSimulationTime();
  /// Replaces the scripted hand (throws uhaptics::Error on invalid options); sim and emulated (the
  /// ticking thread uses it under the device mutex, which this takes).
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
  /// The link to the device as of the last servo tick: kRunning while readings arrive; otherwise
  /// why the tick had none and sent zero (silent or corrupt board: kHostWatchdog, unplugged:
  /// kDisconnected, replugged or rebooted: kConnecting, after getServoLoop()->stop(): kStopped).
  /// getLastFault() is then kDeviceError; getSessionStats() counts the losses and recoveries.
  uhaptics::LinkStatus getLinkStatus();
  /// The board's servo loop (timing statistics, events) on the emulated and usb backends while
  /// open; nullptr on sim.
  uhaptics::ServoLoop* getServoLoop();
  /// Name of the rendering method now in use (may change at run time, e.g. TAU's wall).
  std::string getRendererName() const { return m_policy->name(); }
  /// Whether sense() and render() run in the board's servo thread (emulated, usb) rather than in
  /// the application's calls (sim).
  bool rendersInServoThread() const { return m_servoThreadRenders; }
  /// Board backends: how long the application's input may go unpublished before the efforts ramp
  /// to zero [s] (option "stale_time", 0.001..1, default 0.01: ten periods at 1 kHz, room for a
  /// scene's slow collision query; a paced haptic loop is not throttled by the kernel, see getPaced()).
  double getStaleTime() const { return m_staleTime; }
  /// Whether setForceAndTorqueAndGripperForce() waits for the next servo period (option "pace",
  /// default 1). CHAI3D's haptic loop then runs at the device's rate instead of spinning a core at
  /// SCHED_FIFO, which the kernel's real-time throttling would suspend for 50 ms of every second.
  bool getPaced() const { return m_paced; }
  /// Whether the simulated plant is refereed (option "referee", sim and emulated; see the header comment).
  bool getRefereeEnabled() const { return m_referee != nullptr; }
  /// The passivity layer: 0 off (default), 1 on (observer and damping), 2 observe only (option
  /// "passivity"; see the header comment).
  int getPassivityMode() const { return m_passivityMode; }
  /// Per actuated joint, the largest damping the passivity layer may add along that joint's axis
  /// [N m s/rad, or N s/m on a prismatic joint], as set up by the last open(): m_i / (2 T (1 + d)),
  /// m_i = 1 / (M^-1)_ii the inertia a torque on joint i meets (M the policy's joint-space inertia at
  /// rest), T the servo period and d the board's command delay; at most the option
  /// "passivity_max_damping" (0..1e4). Empty while the layer is off or before open(). (Along the
  /// scene's effort e in joint space the cap is 1 / (e^T M^-1 e 2 T (1 + d)).)
  std::vector<double> getPassivityDampingCaps();
  /// Generated energy the passivity layer tolerates before it damps [J] (option
  /// "passivity_energy_threshold", 0..10, default 0): energy the scene's port gave out beyond the
  /// scene's own continuous-time work.
  double getPassivityEnergyThreshold() const { return m_passivityEnergyThreshold; }

 protected:
  /// a_servoPeriod [s]: the device's control period (its board's rate). a_joints, a_actuators: what
  /// its joint I/O carries (checked against the board in open()), at most C_MAX_DOF joints.
  cUhapticsDevice(unsigned int a_deviceNumber, const uhaptics::DeviceSelection& a_selection,
                  double a_servoPeriod, int a_joints, int a_actuators);

  // ---- what a device class supplies ---------------------------------------------------------
  /// In the constructor: the device's rendering policy, and the joints it rests at until opened
  /// (the state the application reads before open()). Its figures go to sessionStats().
  void setPolicy(std::unique_ptr<uhaptics::DevicePolicy> a_policy, const double* a_restJoints);
  /// The "sim" backend's device, made in open(): the device's simulation with the scripted hand as
  /// its user (BoardPlant::setUserForce) or, for a position-driven device, a user of its own.
  virtual std::unique_ptr<uhaptics::BoardPlant> makeSimulatedPlant() = 0;
  /// close(), after the policy's endSession(): drop what referred to the session's joint I/O.
  virtual void sessionClosed() noexcept {}
  /// The joint I/O of the selected backend: makeJointIo() of the registered device for emulated and
  /// usb, the simulated plant for sim. Test fixtures that are not registered devices override it.
  virtual std::unique_ptr<uhaptics::JointIo> makeJointIo();

  /// Fills the fields every uhaptics device shares (manufacturer, no gripper, no switches, position
  /// sensed and actuated, both hands) and whether the orientation is too; without it every angular
  /// limit is 0. The subclass then sets its forces, stiffness, damping and workspace.
  void setCommonSpecifications(const std::string& a_modelName, bool a_orientation);
  /// m_maxLinearDamping (and m_maxAngularDamping when the orientation is sensed) as the device's
  /// parameter file states them (BoardSpec::max_linear_damping, its "stability" section): the
  /// damping scenes should render at the tool. After setCommonSpecifications().
  void setSpecifiedDamping();
  /// Folder of the device parameter files: uhaptics::defaultParamsDirectory() (params_location.hpp).
  static std::string paramsDirectory();
  /// The session statistics: where the policy records its figures (setPolicy's caller passes it).
  uhaptics::SessionStats& sessionStats() noexcept { return m_stats; }
  /// Held while the policy runs; subclass accessors that read its state take it too.
  std::mutex& deviceMutex() { return m_mutex; }

  uhaptics::DeviceSelection m_selection;

 private:
  using Clock = std::chrono::steady_clock;
  using State = uhaptics::SensedState;  // what the device senses (device frame)
  class ServoBridge;
  friend class ServoBridge;
  /// Haptic thread -> servo thread (board backends): what the scene asks for, time-stamped.
  struct ContactInput {
    double force[3], torque[3], seen[3];
    std::int64_t stampNs;     // steady clock
    std::uint64_t sequence;   // 0: nothing published yet this session
  };
  /// Servo thread -> application (board backends): the state after a tick.
  struct PublishedState {
    double position[3], rotation[9], linearVelocity[3], angularVelocity[3], joints[C_MAX_DOF];
    std::uint64_t ticks;
    uhaptics::LinkStatus link;
    uhaptics::Fault fault;
    bool sensed;  // a reading has been sensed this session
    std::int64_t stampNs;  // steady clock, when the servo thread published it
  };

  void advanceLocked(bool a_oneTick) noexcept;
  void tickLocked() noexcept;
  /// Reads the joints and passes them to sense(); false (nothing sensed) when there is no reading.
  bool readJointsLocked(bool a_first) noexcept;
  /// open(), before the policy's reset(): the passivity layer's limits, sensor steps and inertia for
  /// the board m_io opened.
  void configurePassivityLocked();
  /// sense() on positions from the sensors (rates by the estimator).
  void senseLocked(const double* a_positions, std::uint32_t a_sampleUs, bool a_first) noexcept;
  /// render() with the checks every backend applies: a fault or a non-finite effort sends zero.
  uhaptics::Fault renderChecked(const uhaptics::SceneInput& a_input) noexcept;
  /// The user's side of a tick on the simulated or emulated plant: the scene's force a_asked (device
  /// frame) to the referee, and the scripted hand's force, from the true state where the plant has it.
  /// a_seen: the position the scene computed a_asked from (for the hand recording).
  void pushUserSideLocked(double a_time, const uhaptics::Vec3& a_asked, const uhaptics::Vec3& a_seen) noexcept;
  void recordTickLocked(double a_force, uhaptics::Fault a_fault) noexcept;
  void commandZeroLocked() noexcept;
  // Board backends, servo thread.
  void servoTick(const uhaptics::DeviceSnapshot& a_snapshot, double* a_efforts) noexcept;
  void servoNoReading(const uhaptics::DeviceSnapshot& a_snapshot) noexcept;
  void publishStateLocked() noexcept;
  /// Paced: sleep (no lock held) until the next servo period begins, at most one period.
  void waitForNextPeriod(Clock::time_point a_due) const noexcept;
  // Board backends, application side (m_appMutex held): the newest published state.
  void pullStateLocked() noexcept;
  /// The state the application reads, with the lock that guards it: m_mutex on sim (after
  /// advancing the simulation when a_advance), m_appMutex on a board.
  std::unique_lock<std::mutex> lockApplication(bool a_advance);
  const State& applicationState() const noexcept;
  double wallTime() const noexcept;
  void startStatsWriter();
  /// The servo loop's timing so far into m_lastTiming (m_timingMutex held; no loop: unchanged).
  void captureServoTimingLocked() const;
  /// The servo loop's timing so far into m_lastTiming, and no loop to read from here on (close()).
  void detachServoTiming();
  void stopStatsWriter() noexcept;
  void writeStats(const std::string& a_path) noexcept;
  /// The hand recording's rows so far to m_recordPath (nothing before two rows).
  void writeHandRecording() noexcept;

  std::mutex m_mutex;  // the policy's: held by the thread that ticks and by subclass accessors
  std::unique_ptr<uhaptics::DevicePolicy> m_policy;  // setPolicy(); the passivity layer when on
  uhaptics::PassivePolicy* m_passive = nullptr;       // the layer in m_policy, nullptr when off
  const int m_passivityMode;                           // option "passivity"
  const double m_passivityMaxDamping;                  // option "passivity_max_damping", NaN: the inertia's cap alone
  const double m_passivityEnergyThreshold;             // option "passivity_energy_threshold" [J]
  std::array<double, C_MAX_DOF> m_restJoints{};        // setPolicy()
  State m_state;       // the policy's latest sense()
  const double m_servoPeriod;
  const bool m_servoThreadRenders;  // emulated, usb
  const std::shared_ptr<uhaptics::RefereeChannel> m_referee;  // option "referee"; nullptr: none
  const double m_staleTime;         // [s]
  const bool m_paced;               // setForce...() waits for the next servo period
  bool m_lockStep = false;
  bool m_forcesEnabled = true;
  bool m_handEnabled;
  std::unique_ptr<uhaptics::ScriptedHand> m_hand;
  const std::string m_recordPath;                  // DeviceSelection::record_path; empty: none
  std::unique_ptr<uhaptics::HandRecorder> m_recorder;  // made with the device when m_recordPath is set
  const int m_joints, m_actuators;
  std::unique_ptr<uhaptics::JointIo> m_io;  // every backend; opened in open(), closed in close()
  // The board's servo loop, for the statistics' servo_timing: read by the statistics writer and
  // detached by close() before the loop goes, under m_timingMutex (never taken by the servo thread;
  // the loop's timing is wait-free to read). m_lastTiming keeps the closed session's; empty on sim.
  mutable std::mutex m_timingMutex;
  uhaptics::ServoLoop* m_timingLoop = nullptr;
  mutable std::optional<uhaptics::TimingReport> m_lastTiming;
  std::array<double, uhaptics::wire::kMaxChannels> m_positions{}, m_rates{}, m_efforts{};
  uhaptics::JointRateEstimator m_rateEstimator;  // every backend's rates
  bool m_sensedAfterAdvance = false;  // sim: the joints were read right after the last step
  uhaptics::Vec3 m_commandForce = uhaptics::Vec3::Zero();
  uhaptics::Vec3 m_commandTorque = uhaptics::Vec3::Zero();
  std::uint64_t m_ticks = 0;
  Clock::time_point m_origin;
  uhaptics::Fault m_lastFault = uhaptics::Fault::kNone;
  uhaptics::LinkStatus m_linkStatus = uhaptics::LinkStatus::kClosed;
  uhaptics::SessionStats m_stats;
  std::string m_statsPath;
  std::thread m_statsWriter;
  std::mutex m_writerMutex;
  std::condition_variable m_writerWake;
  bool m_writerStop = false;

  // Board backends: the exchange between the application's threads and the servo thread.
  std::unique_ptr<ServoBridge> m_bridge;      // the ServoRenderer the board's servo loop runs
  std::atomic<bool> m_servoArmed{false};      // open() has reset the policy: the servo thread renders
  bool m_servoFirst = true;                   // servo thread: the next reading is the session's first
  ContactInput m_servoInput{};                // servo thread: the newest input it has read
  int m_staleTicks = 0;                       // servo thread: consecutive periods of stale input
  std::array<double, uhaptics::wire::kMaxChannels> m_heldEfforts{};  // the last rendered efforts
  uhaptics::TripleBuffer<ContactInput> m_inputExchange;
  uhaptics::TripleBuffer<PublishedState> m_stateExchange;
  std::mutex m_appMutex;                      // the application's threads among themselves
  State m_appState;                           // what the application reads (board backends)
  PublishedState m_published{};               // the newest publication read (m_appMutex)
  std::uint64_t m_inputSequence = 0;          // m_appMutex
};

}  // namespace chai3d
