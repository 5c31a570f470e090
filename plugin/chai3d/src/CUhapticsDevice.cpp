#include "uhaptics/chai3d/CUhapticsDevice.hpp"

#include "uhaptics/backends/board_catalog.hpp"
#include "uhaptics/backends/device_definition.hpp"
#include "uhaptics/backends/params_location.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace chai3d {
namespace {

uhaptics::Vec3 toEigen(const cVector3d& v) { return uhaptics::Vec3(v(0), v(1), v(2)); }
cVector3d toChai(const uhaptics::Vec3& v) { return cVector3d(v(0), v(1), v(2)); }

}  // namespace

cUhapticsDevice::cUhapticsDevice(unsigned int a_deviceNumber, const uhaptics::DeviceSelection& a_selection,
                                 double a_servoPeriod, int a_joints, int a_actuators)
    : cGenericHapticDevice(a_deviceNumber),
      m_selection(a_selection),
      m_servoPeriod(a_servoPeriod),
      m_handEnabled(a_selection.hand_enabled && a_selection.backend == "sim"),
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
}

cUhapticsDevice::~cUhapticsDevice() { stopStatsWriter(); }

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
                          "CHAI3D device renders in its own ticks)");
  if (options.emulator_control && m_selection.backend != "emulated")
    throw uhaptics::Error("device '" + m_selection.device + "': joint_io.emulator_control needs the emulated backend, not " +
                          m_selection.backend);
  std::unique_ptr<uhaptics::JointIo> io;
  if (m_selection.backend != "sim") {
    io = uhaptics::makeJointIo(m_selection.device, m_selection.backend, options);
  } else {
    const uhaptics::DeviceDefinition& definition = uhaptics::findDevice(m_selection.device);
    io = uhaptics::makeSimJointIo(uhaptics::boardSpec(definition, options.params_dir), [this] { return makeSimulatedPlant(); });
  }
  if (!m_selection.wrap_joint_io) return io;
  io = m_selection.wrap_joint_io(std::move(io));
  if (!io) throw uhaptics::Error("device '" + m_selection.device + "': the selection's wrap_joint_io returned no joint I/O");
  return io;
}

bool cUhapticsDevice::readJointsLocked(bool a_first) noexcept {
  if (!m_io->read(m_positions.data())) return false;
  if (a_first) m_rateEstimator.reset();
  if (!m_io->readRates(m_rates.data())) {
    m_rateEstimator.update(m_positions.data(), m_joints, m_io->sampleTimeUs(), m_rates.data());
  }
  JointReading reading;
  reading.positions = m_positions.data();
  reading.rates = m_rates.data();
  reading.actual = m_io->readActual(m_actual.data()) ? m_actual.data() : m_positions.data();
  reading.first = a_first;
  sense(reading);
  return true;
}

void cUhapticsDevice::commandZeroLocked() noexcept {
  m_efforts.fill(0.0);
  if (m_io) m_io->command(m_efforts.data());
}

bool cUhapticsDevice::open() {
  std::lock_guard<std::mutex> lock(m_mutex);
  if (m_deviceReady) return C_SUCCESS;
  try {
    // The scripted hand's path is in workspace radii: scale it to this device now that the
    // subclass has filled in its specification.
    m_hand = std::make_unique<uhaptics::ScriptedHand>(m_hand->options(), m_specifications.m_workspaceRadius,
                                                      uhaptics::Vec3::Zero());
    m_io = makeJointIo();
    m_io->open();  // throws with what to do: no board found (and what was), permission, version
    const uhaptics::DeviceDescriptor& d = m_io->spec().descriptor;
    if (d.joints != m_joints || d.actuators != m_actuators) {
      throw uhaptics::Error("'" + m_io->describe() + "' has " + std::to_string(d.joints) + " joints and " +
                            std::to_string(d.actuators) + " actuators; device '" + m_selection.device + "' needs " +
                            std::to_string(m_joints) + " and " + std::to_string(m_actuators));
    }
    resetRendering();
    // A board's servo loop connects in open(); its first STATE takes a few periods.
    constexpr double kFirstReadingTimeout = 2.0;  // [s]
    const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(kFirstReadingTimeout));
    while (!readJointsLocked(true)) {
      commandZeroLocked();
      if (Clock::now() > deadline) {
        throw uhaptics::Error("no joint reading from '" + m_io->describe() + "' within " +
                              std::to_string(kFirstReadingTimeout) + " s");
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    checkFirstReading();
    m_sensedAfterAdvance = true;  // the first tick renders from this reading
  } catch (const std::exception& e) {
    if (m_io) m_io->close();  // nothing half-open: no servo thread, nothing commanded
    m_io.reset();
    std::fprintf(stderr, "uhaptics: cannot open device '%s' (backend %s): %s\n", m_selection.device.c_str(),
                 m_selection.backend.c_str(), e.what());
    return C_ERROR;
  }
  m_commandForce.setZero();
  m_commandTorque.setZero();
  m_ticks = 0;
  m_lastFault = uhaptics::Fault::kNone;
  m_linkStatus = m_io->linkStatus();
  m_origin = Clock::now();
  m_stats.start(wallTime());
  m_deviceReady = true;
  startStatsWriter();
  return C_SUCCESS;
}

bool cUhapticsDevice::close() {
  {
    std::lock_guard<std::mutex> lock(m_mutex);
    if (!m_deviceReady) return C_SUCCESS;
    m_deviceReady = false;
    commandZeroLocked();
    endSession();
    m_io->close();  // zero effort, servo thread stopped, interface released
    m_io.reset();
  }
  stopStatsWriter();
  writeStats(m_statsPath);
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
  std::lock_guard<std::mutex> lock(m_mutex);
  return static_cast<double>(m_ticks) * m_servoPeriod;
}

void cUhapticsDevice::setScriptedHand(const uhaptics::ScriptedHandOptions& a_options) {
  auto hand = std::make_unique<uhaptics::ScriptedHand>(a_options, m_specifications.m_workspaceRadius,
                                                       uhaptics::Vec3::Zero());
  std::lock_guard<std::mutex> lock(m_mutex);
  m_hand = std::move(hand);
}

void cUhapticsDevice::setScriptedHandEnabled(bool a_enabled) {
  std::lock_guard<std::mutex> lock(m_mutex);
  m_handEnabled = a_enabled && m_selection.backend == "sim";
}

void cUhapticsDevice::setStatsFile(const std::string& a_path) {
  std::lock_guard<std::mutex> lock(m_mutex);
  if (m_deviceReady) return;  // the writer thread owns its copy until close()
  m_statsPath = a_path;
}

uhaptics::SessionStatsSnapshot cUhapticsDevice::getSessionStats() const { return m_stats.snapshot(wallTime()); }

uhaptics::LinkStatus cUhapticsDevice::getLinkStatus() {
  std::lock_guard<std::mutex> lock(m_mutex);
  return m_deviceReady ? m_linkStatus : uhaptics::LinkStatus::kClosed;
}

uhaptics::Fault cUhapticsDevice::getLastFault() {
  std::lock_guard<std::mutex> lock(m_mutex);
  return m_lastFault;
}

void cUhapticsDevice::tickLocked() noexcept {
  const double t = static_cast<double>(m_ticks) * m_servoPeriod;
  const bool sendForce = m_forcesEnabled;
  uhaptics::Fault fault = uhaptics::Fault::kNone;
  double output = 0.0;
  const uhaptics::Vec3 seen = m_state.position;
  // A board's newest sample now; a simulation's reading from right after its last step.
  const bool reading = m_sensedAfterAdvance || readJointsLocked(false);
  m_linkStatus = m_io->linkStatus();
  m_stats.recordReading(reading);
  if (!reading) {
    commandZeroLocked();
    readingLost();
    fault = uhaptics::Fault::kDeviceError;
  } else {
    ServoInput input;
    input.force = sendForce ? m_commandForce : uhaptics::Vec3::Zero();
    input.torque = sendForce ? m_commandTorque : uhaptics::Vec3::Zero();
    input.seenPosition = seen;
    input.dt = m_servoPeriod;
    input.time = t;
    fault = render(input, m_efforts.data());
    bool finite = true;
    for (int i = 0; i < m_actuators; ++i) finite = finite && std::isfinite(m_efforts[i]);
    if (fault != uhaptics::Fault::kNone || !finite) {
      if (fault == uhaptics::Fault::kNone) fault = uhaptics::Fault::kNonFiniteResult;
      m_efforts.fill(0.0);
    }
    for (int i = 0; i < m_actuators; ++i) output = std::max(output, std::abs(m_efforts[i]));
    m_io->command(m_efforts.data());
  }
  if (m_handEnabled) {
    m_io->setUserForce(deviceToModelForce(m_hand->force(t, m_state.position, m_state.linearVelocity)));
  }
  const uhaptics::Fault backend = m_io->advance(m_servoPeriod);
  if (fault == uhaptics::Fault::kNone) fault = backend;
  // A simulation moved only now: sense its new state, which the application reads next.
  m_sensedAfterAdvance = m_io->movesOnlyInAdvance() && readJointsLocked(false);
  m_lastFault = fault;
  ++m_ticks;
  m_stats.recordTick(sendForce ? m_commandForce.norm() : 0.0, output, m_lastFault != uhaptics::Fault::kNone);
  const double radius = m_specifications.m_workspaceRadius;
  if (radius > 0.0) {
    m_stats.recordPosition(m_state.position.x() / radius, m_state.position.y() / radius, m_state.position.z() / radius);
  }
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

bool cUhapticsDevice::getPosition(cVector3d& a_position) {
  std::lock_guard<std::mutex> lock(m_mutex);
  if (!m_lockStep) advanceLocked(false);  // a read-only application still sees the hand move it
  a_position = toChai(m_state.position);
  m_linearVelocity = toChai(m_state.linearVelocity);  // the state knows it: no finite-difference estimate
  return m_deviceReady;
}

bool cUhapticsDevice::getRotation(cMatrix3d& a_rotation) {
  std::lock_guard<std::mutex> lock(m_mutex);
  const uhaptics::Mat3& r = m_state.rotation;
  a_rotation.set(r(0, 0), r(0, 1), r(0, 2), r(1, 0), r(1, 1), r(1, 2), r(2, 0), r(2, 1), r(2, 2));
  m_angularVelocity = toChai(m_state.angularVelocity);
  return m_deviceReady;
}

bool cUhapticsDevice::getLinearVelocity(cVector3d& a_linearVelocity) {
  std::lock_guard<std::mutex> lock(m_mutex);
  a_linearVelocity = m_linearVelocity = toChai(m_state.linearVelocity);
  return m_deviceReady;
}

bool cUhapticsDevice::getAngularVelocity(cVector3d& a_angularVelocity) {
  std::lock_guard<std::mutex> lock(m_mutex);
  a_angularVelocity = m_angularVelocity = toChai(m_state.angularVelocity);
  return m_deviceReady;
}

bool cUhapticsDevice::getVelocities(cVector3d& a_linearVelocity, cVector3d& a_angularVelocity) {
  std::lock_guard<std::mutex> lock(m_mutex);
  a_linearVelocity = m_linearVelocity = toChai(m_state.linearVelocity);
  a_angularVelocity = m_angularVelocity = toChai(m_state.angularVelocity);
  return m_deviceReady;
}

bool cUhapticsDevice::getJointAnglesRad(double a_jointAnglesRad[C_MAX_DOF]) {
  std::lock_guard<std::mutex> lock(m_mutex);
  for (int i = 0; i < C_MAX_DOF; ++i) a_jointAnglesRad[i] = i < m_state.joints.size() ? m_state.joints(i) : 0.0;
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
  std::lock_guard<std::mutex> lock(m_mutex);
  if (!m_deviceReady) return C_ERROR;
  m_commandForce = toEigen(a_force);
  m_commandTorque = toEigen(a_torque);
  if (!m_commandForce.allFinite() || !m_commandTorque.allFinite()) {
    // A broken scene must not move the device: zero command; the device reports the fault.
    m_commandForce.setZero();
    m_commandTorque.setZero();
    m_lastFault = uhaptics::Fault::kNonFiniteInput;
    m_stats.recordFault();
    return C_ERROR;
  }
  m_prevForce = a_force;
  m_prevTorque = a_torque;
  m_prevGripperForce = a_gripperForce;
  advanceLocked(m_lockStep);
  return m_deviceReady;
}

bool cUhapticsDevice::enableForces(bool a_value) {
  std::lock_guard<std::mutex> lock(m_mutex);
  m_forcesEnabled = a_value;
  return C_SUCCESS;
}

void cUhapticsDevice::startStatsWriter() {
  if (m_statsPath.empty()) return;
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

}  // namespace chai3d
