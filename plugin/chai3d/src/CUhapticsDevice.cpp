#include "uhaptics/chai3d/CUhapticsDevice.hpp"

#include "uhaptics/backends/board_catalog.hpp"
#include "uhaptics/backends/device_definition.hpp"
#include "uhaptics/backends/params_location.hpp"
#include "uhaptics/chai3d/vector_conversions.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>

namespace chai3d {
namespace {

std::int64_t steadyNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

}  // namespace

// What the board's servo loop runs each period: the device's policy (sense, render) on that
// period's reading.
class cUhapticsDevice::ServoBridge final : public uhaptics::ServoRenderer {
 public:
  explicit ServoBridge(cUhapticsDevice& a_device) : m_device(a_device) {}
  void render(const uhaptics::DeviceSnapshot& a_state, const uhaptics::EffortRequest&, double* a_efforts) noexcept override {
    m_device.servoTick(a_state, a_efforts);
  }
  void noReading(const uhaptics::DeviceSnapshot& a_state) noexcept override { m_device.servoNoReading(a_state); }

 private:
  cUhapticsDevice& m_device;
};

cUhapticsDevice::cUhapticsDevice(unsigned int a_deviceNumber, const uhaptics::DeviceSelection& a_selection,
                                 double a_servoPeriod, int a_joints, int a_actuators)
    : cGenericHapticDevice(a_deviceNumber),
      m_selection(a_selection),
      m_passivityMode(static_cast<int>(a_selection.option("passivity", 0.0, 0.0, 2.0))),
      m_passivityMaxDamping(a_selection.option("passivity_max_damping", std::nan(""), 0.0, 1e4)),
      m_passivityEnergyThreshold(a_selection.option("passivity_energy_threshold", 0.0, 0.0, 10.0)),
      m_servoPeriod(a_servoPeriod),
      m_servoThreadRenders(a_selection.backend != "sim"),
      m_referee(a_selection.backend != "usb" && a_selection.option("referee", 1.0, 0.0, 1.0) != 0.0
                    ? std::make_shared<uhaptics::RefereeChannel>()
                    : nullptr),
      m_staleTime(a_selection.option("stale_time", 0.01, 0.001, 1.0)),
      m_paced(a_selection.option("pace", 1.0, 0.0, 1.0) != 0.0),
      m_handEnabled(a_selection.hand_enabled && a_selection.backend != "usb"),
      m_recordPath(a_selection.record_path),
      m_joints(a_joints),
      m_actuators(a_actuators),
      m_statsPath(a_selection.stats_path) {
  if (!(a_servoPeriod > 0.0) || !std::isfinite(a_servoPeriod)) {
    throw uhaptics::Error("servo period must be finite and > 0");
  }
  if (a_joints < 1 || a_joints > C_MAX_DOF || a_actuators < 1 || a_actuators > uhaptics::wire::kMaxChannels) {
    throw uhaptics::Error("a device needs 1.." + std::to_string(C_MAX_DOF) + " joints and 1.." +
                          std::to_string(uhaptics::wire::kMaxChannels) + " actuators");
  }
  m_deviceNumber = static_cast<int>(a_deviceNumber);  // cGenericDevice ignores its argument
  m_deviceAvailable = true;
  m_deviceReady = false;
  m_hand = std::make_unique<uhaptics::ScriptedHand>(a_selection.hand, 1.0, uhaptics::Vec3::Zero());
  if (!m_recordPath.empty()) {
    m_recorder = std::make_unique<uhaptics::HandRecorder>(
        1.0 / kHandRecordingRate, static_cast<std::size_t>(kHandRecordingRate * kHandRecordingSeconds));
  }
  m_bridge = std::make_unique<ServoBridge>(*this);
}

cUhapticsDevice::~cUhapticsDevice() {
  // Subclasses close() in their destructors; a device left open here still must not leave a servo
  // thread calling into this object's (or a destroyed subclass's) members.
  m_servoArmed.store(false);
  if (m_io) m_io->close();
  stopStatsWriter();
}

void cUhapticsDevice::setCommonSpecifications(const std::string& a_modelName, bool a_orientation) {
  m_specifications.m_model = C_HAPTIC_DEVICE_CUSTOM;
  m_specifications.m_modelName = a_modelName + " (uhaptics, " + m_selection.backend + ")";
  m_specifications.m_manufacturerName = "uhaptics";
  m_specifications.m_maxGripperForce = 0.0;
  m_specifications.m_maxGripperLinearStiffness = 0.0;
  m_specifications.m_maxGripperAngularDamping = 0.0;
  m_specifications.m_gripperMaxAngleRad = 0.0;
  m_specifications.m_sensedGripper = false;
  m_specifications.m_actuatedGripper = false;
  m_specifications.m_sensedPosition = true;
  m_specifications.m_actuatedPosition = true;
  m_specifications.m_sensedRotation = a_orientation;
  m_specifications.m_actuatedRotation = a_orientation;
  m_specifications.m_rightHand = true;
  m_specifications.m_leftHand = true;
  if (!a_orientation) {
    m_specifications.m_maxAngularTorque = 0.0;
    m_specifications.m_maxAngularStiffness = 0.0;
    m_specifications.m_maxAngularDamping = 0.0;
  }
}

void cUhapticsDevice::setSpecifiedDamping() {
  const std::string dir = m_selection.joint_io.params_dir.empty() ? paramsDirectory() : m_selection.joint_io.params_dir;
  const uhaptics::BoardSpec spec = uhaptics::boardSpec(uhaptics::findDevice(m_selection.device), dir);
  m_specifications.m_maxLinearDamping = spec.max_linear_damping;
  if (m_specifications.m_sensedRotation) m_specifications.m_maxAngularDamping = spec.max_angular_damping;
}

void cUhapticsDevice::setPolicy(std::unique_ptr<uhaptics::DevicePolicy> a_policy, const double* a_restJoints) {
  static_assert(uhaptics::kMaxSensedJoints == C_MAX_DOF, "a policy reports as many joints as CHAI3D takes");
  if (!a_policy) throw uhaptics::Error("device '" + m_selection.device + "': no rendering policy");
  m_policy = std::move(a_policy);
  if (m_passivityMode != 0) {
    // Set up for real in open(), from the board it opens; until then it observes only.
    uhaptics::PassivePolicy::Options options;
    options.actuators = m_actuators;
    options.controller.enabled = false;
    auto passive = std::make_unique<uhaptics::PassivePolicy>(std::move(m_policy), options, m_stats);
    m_passive = passive.get();
    m_policy = std::move(passive);
  }
  std::copy(a_restJoints, a_restJoints + m_joints, m_restJoints.begin());
  const std::array<double, C_MAX_DOF> rates{};
  m_policy->sense(uhaptics::SensedJoints{a_restJoints, rates.data(), true}, m_state);  // at rest until opened
}

void cUhapticsDevice::configurePassivityLocked() {
  uhaptics::ScenePortPassivityOptions board = uhaptics::boardPassivityOptions(m_io->spec());
  board.enabled = m_passivityMode == 1;
  board.energy_threshold = m_passivityEnergyThreshold;
  board.max_damping = m_passivityMaxDamping;
  uhaptics::PassivePolicy::Options options =
      uhaptics::passivePolicyOptions(m_passive->wrapped(), m_restJoints.data(), m_joints, m_actuators, board);
  const std::array<double, C_MAX_DOF> rates{};
  m_policy->sense(uhaptics::SensedJoints{m_restJoints.data(), rates.data(), true}, m_state);
  m_passive->configure(options);
}

std::vector<double> cUhapticsDevice::getPassivityDampingCaps() {
  std::lock_guard<std::mutex> lock(m_mutex);
  if (m_passive == nullptr || m_passivityMode == 0 || !m_io) return {};
  const auto& controller = m_passive->controller();
  std::vector<double> caps(static_cast<std::size_t>(m_actuators));
  for (int i = 0; i < m_actuators; ++i)
    caps[static_cast<std::size_t>(i)] =
        controller.capAlong(uhaptics::ScenePortPassivity::Vector::Unit(m_actuators, i), m_servoPeriod);
  return caps;
}

std::string cUhapticsDevice::paramsDirectory() {
  return uhaptics::defaultParamsDirectory();
}

double cUhapticsDevice::wallTime() const noexcept {
  return std::chrono::duration<double>(Clock::now().time_since_epoch()).count();
}

std::unique_ptr<uhaptics::JointIo> cUhapticsDevice::makeJointIo() {
  uhaptics::JointIoOptions options = m_selection.joint_io;
  if (options.params_dir.empty()) options.params_dir = paramsDirectory();
  if (options.renderer != nullptr)
    throw uhaptics::Error("device '" + m_selection.device + "': the selection's joint_io.renderer must be empty (the "
                          "CHAI3D device runs its own policy in the servo thread)");
  if (options.emulator_control && m_selection.backend != "emulated")
    throw uhaptics::Error("device '" + m_selection.device + "': joint_io.emulator_control needs the emulated backend, not " +
                          m_selection.backend);
  std::unique_ptr<uhaptics::JointIo> io;
  if (m_selection.backend != "sim") {
    options.renderer = m_bridge.get();
    // The emulated board's device: with the scripted hand, the same simulated plant as on sim,
    // pushed by the hand each servo period; without it, the board's own device and user.
    if (m_selection.backend == "emulated" && m_handEnabled) options.emulated_plant = [this] { return makeSimulatedPlant(); };
    options.referee = m_referee;
    io = uhaptics::makeJointIo(m_selection.device, m_selection.backend, options);
  } else {
    const uhaptics::DeviceDefinition& definition = uhaptics::findDevice(m_selection.device);
    io = uhaptics::makeSimJointIo(uhaptics::boardSpec(definition, options.params_dir), [this] { return makeSimulatedPlant(); },
                                  m_referee);
  }
  if (!m_selection.wrap_joint_io) return io;
  io = m_selection.wrap_joint_io(std::move(io));
  if (!io) throw uhaptics::Error("device '" + m_selection.device + "': the selection's wrap_joint_io returned no joint I/O");
  return io;
}

bool cUhapticsDevice::readJointsLocked(bool a_first) noexcept {
  if (!m_io->read(m_positions.data())) return false;
  senseLocked(m_positions.data(), m_io->sampleTimeUs(), a_first);
  return true;
}

void cUhapticsDevice::senseLocked(const double* a_positions, std::uint32_t a_sampleUs, bool a_first) noexcept {
  if (a_first) m_rateEstimator.reset();
  m_rateEstimator.update(a_positions, m_joints, a_sampleUs, m_rates.data());
  uhaptics::SensedJoints reading;
  reading.positions = a_positions;
  reading.rates = m_rates.data();
  reading.first = a_first;
  m_policy->sense(reading, m_state);
}

uhaptics::Fault cUhapticsDevice::renderChecked(const uhaptics::SceneInput& a_input) noexcept {
  uhaptics::Fault fault = m_policy->render(a_input, m_efforts.data());
  bool finite = true;
  for (int i = 0; i < m_actuators; ++i) finite = finite && std::isfinite(m_efforts[i]);
  if (fault != uhaptics::Fault::kNone || !finite) {
    if (fault == uhaptics::Fault::kNone) fault = uhaptics::Fault::kNonFiniteResult;
    m_efforts.fill(0.0);
  }
  return fault;
}

void cUhapticsDevice::pushUserSideLocked(double a_time, const uhaptics::Vec3& a_asked,
                                         const uhaptics::Vec3& a_seen) noexcept {
  if (m_referee) m_io->setSceneForce(m_policy->sceneForceAtUserPort(a_asked));
  if (!m_handEnabled) return;
  // The hand holds the device as it is (a damper on an encoder-differenced velocity would lag);
  // a plant without a point for it (its user is its own) is pushed from the sensed state.
  uhaptics::Vec3 position = m_state.position, velocity = m_state.linear_velocity;
  uhaptics::Vec3 modelPosition, modelVelocity;
  if (m_io->readUserPoint(modelPosition, modelVelocity)) {
    position = m_policy->modelToDevicePoint(modelPosition);
    velocity = m_policy->modelToDeviceVector(modelVelocity);
  }
  m_io->setUserForce(m_policy->deviceToModelForce(m_hand->force(a_time, position, velocity)));
  const double radius = m_specifications.m_workspaceRadius;
  if (m_recorder && radius > 0.0 && m_recorder->due(a_time)) {
    uhaptics::HandSample row;
    row.time = a_time;
    m_hand->anchor(a_time, row.anchor, row.anchor_velocity);
    row.anchor /= radius;  // the hand's centre is the workspace centre, the device frame's origin
    row.anchor_velocity /= radius;
    const uhaptics::ScriptedHand::Grip grip = m_hand->grip(a_time);
    row.stiffness = grip.stiffness;
    row.damping = grip.damping;
    row.max_force = grip.max_force;
    row.scene_force = a_asked;
    row.scene_position = a_seen / radius;
    m_recorder->record(row);
  }
}

void cUhapticsDevice::recordTickLocked(double a_force, uhaptics::Fault a_fault) noexcept {
  double output = 0.0;
  for (int i = 0; i < m_actuators; ++i) output = std::max(output, std::abs(m_efforts[i]));
  m_stats.recordTick(a_force, output, a_fault != uhaptics::Fault::kNone);
  const double radius = m_specifications.m_workspaceRadius;
  if (radius > 0.0) {
    m_stats.recordPosition(m_state.position.x() / radius, m_state.position.y() / radius, m_state.position.z() / radius);
  }
}

void cUhapticsDevice::commandZeroLocked() noexcept {
  m_efforts.fill(0.0);
  if (m_io) m_io->command(m_efforts.data());
}

bool cUhapticsDevice::open() {
  std::unique_lock<std::mutex> lock(m_mutex);
  if (m_deviceReady) return C_SUCCESS;
  try {
    // The scripted hand's path is in workspace radii: scale it to this device now that the
    // subclass has filled in its specification.
    m_hand = std::make_unique<uhaptics::ScriptedHand>(m_hand->options(), m_specifications.m_workspaceRadius,
                                                      uhaptics::Vec3::Zero());
    if (m_recorder) m_recorder->clear();  // the writer thread is stopped while closed
    m_io = makeJointIo();
    m_servoArmed.store(false);  // a board's servo thread sends zero until the policy is reset
    m_rateEstimator.setResolution(m_io->spec().position_resolution.data(), m_joints);
    // Over the board protocol a command acts a period after its reading: the policy is designed for
    // it before the board starts (an LQR design takes tens of ms, and until the policy is armed the
    // servo thread commands zero: the device would sag meanwhile).
    m_policy->reset(m_io->commandDelayPeriods());
    m_io->open();  // throws with what to do: no board found (and what was), permission, version
    {
      std::lock_guard<std::mutex> timing(m_timingMutex);
      m_timingLoop = m_io->servoLoop();
      m_lastTiming.reset();
    }
    const uhaptics::DeviceDescriptor& d = m_io->spec().descriptor;
    if (d.joints != m_joints || d.actuators != m_actuators) {
      throw uhaptics::Error("'" + m_io->describe() + "' has " + std::to_string(d.joints) + " joints and " +
                            std::to_string(d.actuators) + " actuators; device '" + m_selection.device + "' needs " +
                            std::to_string(m_joints) + " and " + std::to_string(m_actuators));
    }
    if (m_passive != nullptr) configurePassivityLocked();
    m_ticks = 0;
    m_lastFault = uhaptics::Fault::kNone;
    m_stats.start(wallTime());
    // A board's servo loop connects in open(); its first STATE takes a few periods.
    constexpr double kFirstReadingTimeout = 2.0;  // [s]
    const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(kFirstReadingTimeout));
    const auto noReading = [&] {
      if (Clock::now() > deadline) {
        throw uhaptics::Error("no joint reading from '" + m_io->describe() + "' within " +
                              std::to_string(kFirstReadingTimeout) + " s");
      }
    };
    if (m_servoThreadRenders) {
      // The servo thread senses its first reading (and renders zero input: none is published).
      {
        std::lock_guard<std::mutex> app(m_appMutex);
        m_inputSequence = 0;
        m_published = PublishedState{};
      }
      m_servoFirst = true;
      m_staleTicks = 0;
      m_heldEfforts.fill(0.0);
      m_servoInput = ContactInput{};
      m_servoArmed.store(true, std::memory_order_release);
      lock.unlock();
      for (;;) {
        {
          std::lock_guard<std::mutex> app(m_appMutex);
          pullStateLocked();
          if (m_published.sensed) break;
        }
        noReading();
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
      }
      lock.lock();
    } else {
      while (!readJointsLocked(true)) {
        commandZeroLocked();
        noReading();
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
      }
      m_sensedAfterAdvance = true;  // the first tick renders from this reading
    }
    m_policy->checkFirstReading();
  } catch (const std::exception& e) {
    m_servoArmed.store(false);
    if (lock.owns_lock()) lock.unlock();  // the servo thread may be waiting for it to finish its period
    detachServoTiming();
    if (m_io) m_io->close();  // nothing half-open: no servo thread, nothing commanded
    lock.lock();
    m_io.reset();
    std::fprintf(stderr, "uhaptics: cannot open device '%s' (backend %s): %s\n", m_selection.device.c_str(),
                 m_selection.backend.c_str(), e.what());
    return C_ERROR;
  }
  m_commandForce.setZero();
  m_commandTorque.setZero();
  if (!m_servoThreadRenders) m_linkStatus = m_io->linkStatus();
  m_origin = Clock::now();
  {
    std::lock_guard<std::mutex> app(m_appMutex);  // the application's getters read it under this lock on a board
    m_deviceReady = true;
  }
  startStatsWriter();
  return C_SUCCESS;
}

bool cUhapticsDevice::close() {
  {
    std::unique_lock<std::mutex> lock(m_mutex);
    if (!m_deviceReady) return C_SUCCESS;
    {
      std::lock_guard<std::mutex> app(m_appMutex);
      m_deviceReady = false;
    }
    m_servoArmed.store(false);  // the servo thread's next periods send zero
    commandZeroLocked();
    m_policy->endSession();
    sessionClosed();
    lock.unlock();  // a servo period in progress finishes first
    detachServoTiming();
    m_io->close();  // zero effort, servo thread stopped, interface released
    lock.lock();
    m_io.reset();
  }
  stopStatsWriter();
  writeStats(m_statsPath);
  writeHandRecording();
  if (m_recorder && m_recorder->dropped() > 0) {
    std::fprintf(stderr, "uhaptics: the hand recording %s holds the first %.0f s; %zu later rows did not fit\n",
                 m_recordPath.c_str(), kHandRecordingSeconds, m_recorder->dropped());
  }
  return C_SUCCESS;
}

bool cUhapticsDevice::calibrate(bool) { return m_deviceReady; }

uhaptics::ServoLoop* cUhapticsDevice::getServoLoop() {
  std::lock_guard<std::mutex> lock(m_mutex);
  return m_io ? m_io->servoLoop() : nullptr;
}

void cUhapticsDevice::setLockStep(bool a_lockStep) {
  std::lock_guard<std::mutex> lock(m_mutex);
  m_lockStep = a_lockStep;
}

double cUhapticsDevice::getSimulationTime() {
  const auto lock = lockApplication(false);
  return static_cast<double>(m_servoThreadRenders ? m_published.ticks : m_ticks) * m_servoPeriod;
}

void cUhapticsDevice::setScriptedHand(const uhaptics::ScriptedHandOptions& a_options) {
  auto hand = std::make_unique<uhaptics::ScriptedHand>(a_options, m_specifications.m_workspaceRadius,
                                                       uhaptics::Vec3::Zero());
  std::lock_guard<std::mutex> lock(m_mutex);
  m_hand = std::move(hand);
}

void cUhapticsDevice::setScriptedHandEnabled(bool a_enabled) {
  std::lock_guard<std::mutex> lock(m_mutex);
  // On emulated the choice also picks the board's device (open() makes it): only while closed.
  if (m_selection.backend == "sim" || (m_selection.backend == "emulated" && !m_deviceReady)) m_handEnabled = a_enabled;
}

void cUhapticsDevice::setStatsFile(const std::string& a_path) {
  std::lock_guard<std::mutex> lock(m_mutex);
  if (m_deviceReady) return;  // the writer thread owns its copy until close()
  m_statsPath = a_path;
}

uhaptics::SessionStatsSnapshot cUhapticsDevice::getSessionStats() const {
  uhaptics::SessionStatsSnapshot snapshot = m_stats.snapshot(wallTime());
  if (m_referee) {
    snapshot.has_referee = true;
    snapshot.referee = m_referee->latest();
  }
  std::lock_guard<std::mutex> timing(m_timingMutex);
  captureServoTimingLocked();
  snapshot.has_servo_timing = m_lastTiming.has_value();
  if (m_lastTiming) snapshot.servo_timing = *m_lastTiming;
  return snapshot;
}

void cUhapticsDevice::captureServoTimingLocked() const {
  if (m_timingLoop != nullptr) m_lastTiming = m_timingLoop->timing();
}

void cUhapticsDevice::detachServoTiming() {
  std::lock_guard<std::mutex> timing(m_timingMutex);
  captureServoTimingLocked();  // the session's last word, kept for the final statistics
  m_timingLoop = nullptr;
}

uhaptics::LinkStatus cUhapticsDevice::getLinkStatus() {
  const auto lock = lockApplication(false);
  if (!m_deviceReady) return uhaptics::LinkStatus::kClosed;
  return m_servoThreadRenders ? m_published.link : m_linkStatus;
}

uhaptics::Fault cUhapticsDevice::getLastFault() {
  const auto lock = lockApplication(false);
  return m_servoThreadRenders ? m_published.fault : m_lastFault;
}

void cUhapticsDevice::tickLocked() noexcept {
  const double t = static_cast<double>(m_ticks) * m_servoPeriod;
  const bool sendForce = m_forcesEnabled;
  uhaptics::Fault fault = uhaptics::Fault::kNone;
  const uhaptics::Vec3 seen = m_state.position;
  // The reading from right after the simulation's last step.
  const bool reading = m_sensedAfterAdvance || readJointsLocked(false);
  m_linkStatus = m_io->linkStatus();
  m_stats.recordReading(reading);
  if (!reading) {
    commandZeroLocked();
    m_policy->readingLost();
    fault = uhaptics::Fault::kDeviceError;
  } else {
    uhaptics::SceneInput input;
    input.force = sendForce ? m_commandForce : uhaptics::Vec3::Zero();
    input.torque = sendForce ? m_commandTorque : uhaptics::Vec3::Zero();
    input.seen_position = seen;
    input.dt = m_servoPeriod;
    input.time = t;
    fault = renderChecked(input);
    m_io->command(m_efforts.data());
  }
  pushUserSideLocked(t, reading && sendForce ? m_commandForce : uhaptics::Vec3::Zero(), seen);
  const uhaptics::Fault backend = m_io->advance(m_servoPeriod);
  if (fault == uhaptics::Fault::kNone) fault = backend;
  // The simulation moved only now: sense its new state, which the application reads next.
  m_sensedAfterAdvance = m_io->movesOnlyInAdvance() && readJointsLocked(false);
  m_lastFault = fault;
  ++m_ticks;
  recordTickLocked(sendForce ? m_commandForce.norm() : 0.0, m_lastFault);
}

void cUhapticsDevice::servoTick(const uhaptics::DeviceSnapshot& a_snapshot, double* a_efforts) noexcept {
  std::fill(a_efforts, a_efforts + m_actuators, 0.0);
  if (!m_servoArmed.load(std::memory_order_acquire)) return;  // open() has not reset the policy yet
  std::lock_guard<std::mutex> lock(m_mutex);
  if (!m_servoArmed.load(std::memory_order_relaxed)) return;  // close() came first
  const double t = static_cast<double>(m_ticks) * m_servoPeriod;
  const uhaptics::Vec3 sensedBefore = m_state.position;
  senseLocked(a_snapshot.position.data(), a_snapshot.sample_time_us[0], m_servoFirst);
  const bool first = m_servoFirst;
  m_servoFirst = false;
  m_stats.recordReading(true);
  m_linkStatus = uhaptics::LinkStatus::kRunning;

  // The application's input: nothing published yet is a zero force (an application that only
  // reads the device); published and then silent past the stale time is a stall.
  m_inputExchange.read(m_servoInput);
  const bool published = m_servoInput.sequence != 0;
  const bool stale = published && static_cast<double>(steadyNs() - m_servoInput.stampNs) > m_staleTime * 1e9;
  m_stats.recordInput(stale);
  uhaptics::Fault fault = uhaptics::Fault::kNone;
  double force = 0.0;
  uhaptics::Vec3 asked = uhaptics::Vec3::Zero();  // what the scene asks now (nothing while stale)
  uhaptics::Vec3 seen = m_state.position;          // and where it saw the tool
  if (!stale) {
    uhaptics::SceneInput input;
    input.force = published ? uhaptics::Vec3(m_servoInput.force[0], m_servoInput.force[1], m_servoInput.force[2])
                            : uhaptics::Vec3::Zero();
    input.torque = published ? uhaptics::Vec3(m_servoInput.torque[0], m_servoInput.torque[1], m_servoInput.torque[2])
                             : uhaptics::Vec3::Zero();
    input.seen_position = published ? uhaptics::Vec3(m_servoInput.seen[0], m_servoInput.seen[1], m_servoInput.seen[2])
                                   : (first ? m_state.position : sensedBefore);
    input.dt = m_servoPeriod;
    input.time = t;
    fault = renderChecked(input);
    force = input.force.norm();
    asked = input.force;
    seen = input.seen_position;
    m_staleTicks = 0;
    m_heldEfforts = m_efforts;
  } else {
    // A stalled application: its last force no longer belongs to where the device is. End the
    // contact and ramp the last efforts down (no step for the user's hand).
    if (m_staleTicks == 0) m_policy->readingLost();
    ++m_staleTicks;
    const double scale = std::max(0.0, 1.0 - static_cast<double>(m_staleTicks) / kStaleRampPeriods);
    for (int i = 0; i < m_actuators; ++i) m_efforts[i] = scale * m_heldEfforts[i];
  }
  std::copy(m_efforts.begin(), m_efforts.begin() + m_actuators, a_efforts);
  pushUserSideLocked(t, asked, seen);
  m_lastFault = fault;
  ++m_ticks;
  recordTickLocked(force, fault);
  publishStateLocked();
}

void cUhapticsDevice::servoNoReading(const uhaptics::DeviceSnapshot& a_snapshot) noexcept {
  if (!m_servoArmed.load(std::memory_order_acquire)) return;
  std::lock_guard<std::mutex> lock(m_mutex);
  if (!m_servoArmed.load(std::memory_order_relaxed)) return;
  const bool linkDown = a_snapshot.link != uhaptics::LinkState::kRunning || a_snapshot.host_watchdog_tripped;
  if (!linkDown) return;  // one late STATE: the loop holds the previous command
  switch (a_snapshot.link) {
    case uhaptics::LinkState::kConnecting: m_linkStatus = uhaptics::LinkStatus::kConnecting; break;
    case uhaptics::LinkState::kDisconnected: m_linkStatus = uhaptics::LinkStatus::kDisconnected; break;
    case uhaptics::LinkState::kStopped: m_linkStatus = uhaptics::LinkStatus::kStopped; break;
    case uhaptics::LinkState::kRunning: m_linkStatus = uhaptics::LinkStatus::kHostWatchdog; break;
  }
  m_stats.recordReading(false);
  m_policy->readingLost();
  m_efforts.fill(0.0);
  m_heldEfforts.fill(0.0);
  m_servoFirst = true;  // rates start again from the next reading
  m_lastFault = uhaptics::Fault::kDeviceError;
  ++m_ticks;
  recordTickLocked(0.0, m_lastFault);
  publishStateLocked();
}

void cUhapticsDevice::publishStateLocked() noexcept {
  PublishedState p;
  for (int i = 0; i < 3; ++i) {
    p.position[i] = m_state.position(i);
    p.linearVelocity[i] = m_state.linear_velocity(i);
    p.angularVelocity[i] = m_state.angular_velocity(i);
    for (int j = 0; j < 3; ++j) p.rotation[3 * i + j] = m_state.rotation(i, j);
  }
  for (int i = 0; i < C_MAX_DOF; ++i) p.joints[i] = i < m_state.joints.size() ? m_state.joints(i) : 0.0;
  p.ticks = m_ticks;
  p.link = m_linkStatus;
  p.fault = m_lastFault;
  p.sensed = !m_servoFirst || m_ticks > 0;
  p.stampNs = steadyNs();
  m_stateExchange.write(p);
}

void cUhapticsDevice::pullStateLocked() noexcept {
  if (!m_stateExchange.read(m_published) || !m_published.sensed) return;
  const PublishedState& p = m_published;
  m_appState.position = uhaptics::Vec3(p.position[0], p.position[1], p.position[2]);
  m_appState.linear_velocity = uhaptics::Vec3(p.linearVelocity[0], p.linearVelocity[1], p.linearVelocity[2]);
  m_appState.angular_velocity = uhaptics::Vec3(p.angularVelocity[0], p.angularVelocity[1], p.angularVelocity[2]);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) m_appState.rotation(i, j) = p.rotation[3 * i + j];
  m_appState.joints.resize(m_joints);
  for (int i = 0; i < m_joints; ++i) m_appState.joints(i) = p.joints[i];
}

std::unique_lock<std::mutex> cUhapticsDevice::lockApplication(bool a_advance) {
  if (m_servoThreadRenders) {
    std::unique_lock<std::mutex> lock(m_appMutex);
    pullStateLocked();
    return lock;
  }
  std::unique_lock<std::mutex> lock(m_mutex);
  if (a_advance && !m_lockStep) advanceLocked(false);  // a read-only application still sees the hand move it
  return lock;
}

void cUhapticsDevice::advanceLocked(bool a_oneTick) noexcept {
  if (!m_deviceReady) return;
  if (a_oneTick) {
    tickLocked();
    return;
  }
  const double elapsed = std::chrono::duration<double>(Clock::now() - m_origin).count();
  const auto due = static_cast<std::uint64_t>(elapsed / m_servoPeriod);
  if (due <= m_ticks) return;  // the application's loop runs faster than the servo: hold
  std::uint64_t missing = due - m_ticks;
  if (missing > static_cast<std::uint64_t>(kMaxCatchUpTicks)) {
    // The application stalled (a debugger, a descheduled thread): resume from now instead of
    // replaying the gap at once. Moving the origin keeps simulated time continuous.
    m_origin += std::chrono::duration_cast<Clock::duration>(
        std::chrono::duration<double>(static_cast<double>(missing - kMaxCatchUpTicks) * m_servoPeriod));
    missing = kMaxCatchUpTicks;
  }
  for (std::uint64_t i = 0; i < missing; ++i) tickLocked();
}

const cUhapticsDevice::State& cUhapticsDevice::applicationState() const noexcept {
  // Before the first reading of a session (and while closed) the subclass's resting state.
  return m_servoThreadRenders && m_published.sensed ? m_appState : m_state;
}

bool cUhapticsDevice::getPosition(cVector3d& a_position) {
  const auto lock = lockApplication(true);
  const State& state = applicationState();
  a_position = toChai(state.position);
  m_linearVelocity = toChai(state.linear_velocity);  // the state knows it: no finite-difference estimate
  return m_deviceReady;
}

bool cUhapticsDevice::getRotation(cMatrix3d& a_rotation) {
  const auto lock = lockApplication(false);
  const uhaptics::Mat3& r = applicationState().rotation;
  a_rotation.set(r(0, 0), r(0, 1), r(0, 2), r(1, 0), r(1, 1), r(1, 2), r(2, 0), r(2, 1), r(2, 2));
  m_angularVelocity = toChai(applicationState().angular_velocity);
  return m_deviceReady;
}

bool cUhapticsDevice::getLinearVelocity(cVector3d& a_linearVelocity) {
  const auto lock = lockApplication(false);
  a_linearVelocity = m_linearVelocity = toChai(applicationState().linear_velocity);
  return m_deviceReady;
}

bool cUhapticsDevice::getAngularVelocity(cVector3d& a_angularVelocity) {
  const auto lock = lockApplication(false);
  a_angularVelocity = m_angularVelocity = toChai(applicationState().angular_velocity);
  return m_deviceReady;
}

bool cUhapticsDevice::getVelocities(cVector3d& a_linearVelocity, cVector3d& a_angularVelocity) {
  const auto lock = lockApplication(false);
  a_linearVelocity = m_linearVelocity = toChai(applicationState().linear_velocity);
  a_angularVelocity = m_angularVelocity = toChai(applicationState().angular_velocity);
  return m_deviceReady;
}

bool cUhapticsDevice::getJointAnglesRad(double a_jointAnglesRad[C_MAX_DOF]) {
  const auto lock = lockApplication(false);
  const State& state = applicationState();
  for (int i = 0; i < C_MAX_DOF; ++i) a_jointAnglesRad[i] = i < state.joints.size() ? state.joints(i) : 0.0;
  return m_deviceReady;
}

bool cUhapticsDevice::getGripperAngleRad(double& a_angle) {
  a_angle = 0.0;
  return m_deviceReady;
}

bool cUhapticsDevice::getGripperAngularVelocity(double& a_gripperAngularVelocity) {
  a_gripperAngularVelocity = 0.0;
  return m_deviceReady;
}

bool cUhapticsDevice::getUserSwitches(unsigned int& a_userSwitches) {
  a_userSwitches = 0;
  return m_deviceReady;
}

bool cUhapticsDevice::setForceAndTorqueAndGripperForce(const cVector3d& a_force, const cVector3d& a_torque,
                                                       double a_gripperForce) {
  auto lock = lockApplication(false);
  if (!m_deviceReady) return C_ERROR;
  m_commandForce = toEigen(a_force);
  m_commandTorque = toEigen(a_torque);
  const bool finite = m_commandForce.allFinite() && m_commandTorque.allFinite();
  if (!finite) {
    // A broken scene must not move the device: zero command; the device reports the fault.
    m_commandForce.setZero();
    m_commandTorque.setZero();
    if (!m_servoThreadRenders) m_lastFault = uhaptics::Fault::kNonFiniteInput;
    m_stats.recordFault();
  }
  m_prevForce = a_force;
  m_prevTorque = a_torque;
  m_prevGripperForce = a_gripperForce;
  if (m_servoThreadRenders) {
    // The servo thread renders it on its next period; the stamp says how fresh it is.
    ContactInput input;
    const bool send = m_forcesEnabled;
    for (int i = 0; i < 3; ++i) {
      input.force[i] = send ? m_commandForce(i) : 0.0;
      input.torque[i] = send ? m_commandTorque(i) : 0.0;
      input.seen[i] = applicationState().position(i);
    }
    input.stampNs = steadyNs();
    input.sequence = ++m_inputSequence;
    m_inputExchange.write(input);
    if (m_paced) {
      // The servo thread's next period: one period after its latest publication, plus a margin
      // for its read, render and publish.
      const auto published = Clock::time_point(std::chrono::nanoseconds(m_published.stampNs));
      const auto due = published + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(m_servoPeriod)) +
                       std::chrono::microseconds(50);
      lock.unlock();
      waitForNextPeriod(due);
    }
  } else if (finite) {
    advanceLocked(m_lockStep);
    if (m_paced && !m_lockStep) {
      const auto due = m_origin + std::chrono::duration_cast<Clock::duration>(
                                      std::chrono::duration<double>(static_cast<double>(m_ticks + 1) * m_servoPeriod));
      lock.unlock();
      waitForNextPeriod(due);
    }
  }
  return finite ? m_deviceReady : C_ERROR;
}

void cUhapticsDevice::waitForNextPeriod(Clock::time_point a_due) const noexcept {
  // Never longer than one period: a late or stopped servo thread does not hold the application.
  const auto now = Clock::now();
  const auto longest = now + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(m_servoPeriod));
  if (a_due > now) std::this_thread::sleep_until(std::min(a_due, longest));
}

bool cUhapticsDevice::enableForces(bool a_value) {
  const auto lock = lockApplication(false);
  m_forcesEnabled = a_value;
  return C_SUCCESS;
}

void cUhapticsDevice::startStatsWriter() {
  if (m_statsPath.empty() && !m_recorder) return;
  const std::string path = m_statsPath;  // the writer never reads members the app may change
  {
    std::lock_guard<std::mutex> lock(m_writerMutex);
    m_writerStop = false;
  }
  m_statsWriter = std::thread([this, path] {
    std::unique_lock<std::mutex> lock(m_writerMutex);
    while (!m_writerWake.wait_for(lock, std::chrono::milliseconds(500), [this] { return m_writerStop; })) {
      lock.unlock();
      writeStats(path);
      writeHandRecording();  // also a killed process leaves its recording up to the last half second
      lock.lock();
    }
  });
}

void cUhapticsDevice::stopStatsWriter() noexcept {
  {
    std::lock_guard<std::mutex> lock(m_writerMutex);
    m_writerStop = true;
  }
  m_writerWake.notify_all();
  if (m_statsWriter.joinable()) m_statsWriter.join();
}

void cUhapticsDevice::writeStats(const std::string& a_path) noexcept {
  if (a_path.empty()) return;
  try {
    uhaptics::writeFileAtomically(a_path, uhaptics::formatStatsJson(getSessionStats(), m_selection.device,
                                                                         m_selection.backend, getRendererName()));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "uhaptics: %s\n", e.what());
  }
}

void cUhapticsDevice::writeHandRecording() noexcept {
  if (!m_recorder || m_recorder->count() < 2) return;
  try {
    uhaptics::HandRecording recording;
    recording.workspace_radius = m_specifications.m_workspaceRadius;
    recording.device = m_selection.device;
    recording.backend = m_selection.backend;
    const std::size_t rows = m_recorder->count();  // complete rows, never changed while the session runs
    recording.dropped_rows = m_recorder->dropped();
    recording.samples.assign(m_recorder->rows(), m_recorder->rows() + rows);
    uhaptics::writeFileAtomically(m_recordPath, uhaptics::formatHandRecording(recording));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "uhaptics: %s\n", e.what());
  }
}

}  // namespace chai3d
