#include "uhaptics/chai3d/CTauDevice.hpp"

#include <algorithm>
#include <cmath>

#include "uhaptics/backends/tau_plant.hpp"
#include "uhaptics/core/limits.hpp"
#include "uhaptics/models/tau_kinematics.hpp"
#include "uhaptics/renderers/tau_wall_design.hpp"

namespace chai3d {
namespace {

// Paper 001's spring-wall baseline: the device's m_maxLinearStiffness, so CHAI3D's examples set
// their stiffness as a fraction of it; the classifier places the proxy with it until its probe has
// measured the scene's.
constexpr double kSpringWallStiffness = 6000.0;  // N/m

uhaptics::TauContactClassifier::Options classifierOptions(const uhaptics::DeviceSelection& a_selection,
                                                          double a_servoPeriod) {
  uhaptics::TauContactClassifier::Options options;
  options.stiff_threshold = a_selection.option("stiff_threshold", 3000.0, 1.0, 1e6);
  options.contact_force = a_selection.option("contact_force", 0.3, 0.01, 10.0);
  options.release_ticks = static_cast<int>(std::lround(a_selection.option("release_time", 0.05, 0.001, 1.0) / a_servoPeriod));
  options.nominal_stiffness = kSpringWallStiffness;
  options.servo_period = a_servoPeriod;
  return options;
}

uhaptics::TauContactClassifier::WallMode classifierMode(int a_mode) {
  switch (a_mode) {
    case cTauDevice::C_TAU_WALL_SPRING:
      return uhaptics::TauContactClassifier::WallMode::kSpring;
    case cTauDevice::C_TAU_WALL_LQR:
      return uhaptics::TauContactClassifier::WallMode::kLqr;
    default:
      return uhaptics::TauContactClassifier::WallMode::kAuto;
  }
}

}  // namespace

cTauDevice::cTauDevice(unsigned int a_deviceNumber, const uhaptics::DeviceSelection& a_selection)
    : cUhapticsDevice(a_deviceNumber, a_selection, 1e-3, 6, 6),
      m_model(std::make_unique<uhaptics::TauModel>(uhaptics::TauModel::load(paramsDirectory() + "/tau.json"))),
      m_toolDamping(a_selection.option("tool_damping", 0.0, 0.0, 50.0)),
      m_classifier(classifierOptions(a_selection, getServoPeriod())) {
  const uhaptics::TauModel& model = *m_model;
  if (std::abs(model.servoPeriod() - getServoPeriod()) > 1e-12) {
    throw uhaptics::Error("TAU parameter file: the servo period must be 1 ms (the LQR wall is designed for it)");
  }
  m_wallMode = static_cast<int>(a_selection.option("wall", 0.0, 0.0, 2.0));
  m_centre = model.homePose().head<3>();
  m_data = std::make_unique<uhaptics::TauData>(model);
  // LQR gains at the workspace centre (paper 001 linearizes at one operating point), for the
  // undelayed plant until open() knows the backend's command delay (resetRendering()).
  m_lqr = makeWall(0);

  // Force the device can produce in any direction at home: tau = J^T [F; 0] within the torque
  // limits, minimized over a sphere of directions; likewise the torque.
  uhaptics::Mat6 J;
  model.jacobian(model.homeJoints(), J);
  double force = 1e9, torque = 1e9;
  for (int i = -2; i <= 2; ++i)
    for (int j = -2; j <= 2; ++j)
      for (int k = -2; k <= 2; ++k) {
        if (i == 0 && j == 0 && k == 0) continue;
        const uhaptics::Vec3 u = uhaptics::Vec3(i, j, k).normalized();
        uhaptics::Vec6 w = uhaptics::Vec6::Zero();
        w.head<3>() = u;
        force = std::min(force, (model.effortLimits().array() / (J.transpose() * w).array().abs()).minCoeff());
        w.head<3>().setZero();
        w.tail<3>() = u;
        torque = std::min(torque, (model.effortLimits().array() / (J.transpose() * w).array().abs()).minCoeff());
      }

  setCommonSpecifications("TAU-class 6-DoF parallel device", true);
  m_specifications.m_maxLinearForce = force;
  m_specifications.m_maxAngularTorque = torque;
  m_specifications.m_maxLinearStiffness = kSpringWallStiffness;
  m_specifications.m_maxAngularStiffness = 1.0;    // assumed: mild rotational springs
  m_specifications.m_maxLinearDamping = 4.0;       // paper 001: Colgate's bound b > K T / 2 for 6000 N/m at 1 kHz
  m_specifications.m_maxAngularDamping = 0.01;     // assumed
  m_specifications.m_workspaceRadius = model.workspaceHalfSide();  // the 50 mm cube's inscribed sphere
  m_q = model.homeJoints();
  updateState(*m_data, m_q);  // at home, at rest until opened

  using Kind = uhaptics::RendererFigure::Kind;
  uhaptics::SessionStats& stats = sessionStats();
  m_figEngagements = stats.declareFigure("lqr_engagements", Kind::kCount);
  m_figReleases = stats.declareFigure("lqr_releases", Kind::kCount);
  m_figHeldTicks = stats.declareFigure("lqr_held_ticks", Kind::kCount);
  m_figEntryDepth = stats.declareFigure("max_entry_depth_mm", Kind::kMaximum);
  m_figMaxPenetration = stats.declareFigure("max_penetration_mm", Kind::kMaximum);
  m_figSaturatedTicks = stats.declareFigure("lqr_saturated_ticks", Kind::kCount);
  m_figSpringTicks = stats.declareFigure("spring_contact_ticks", Kind::kCount);
  m_figSoftContacts = stats.declareFigure("soft_surface_contacts", Kind::kCount);
  m_figSoftStiffness = stats.declareFigure("soft_stiffness_max_N_per_m", Kind::kMaximum);
  m_figOverloads = stats.declareFigure("lqr_overloads", Kind::kCount);
}

cTauDevice::~cTauDevice() { close(); }

std::string cTauDevice::getRendererName() const {
  if (m_lqrEngaged.load()) return "LQR wall";
  return m_wallMode.load() == C_TAU_WALL_SPRING ? "spring (J^T F)" : "spring (J^T F), LQR wall on stiff contact";
}

void cTauDevice::setWallMode(cWallMode a_mode) { m_wallMode = a_mode; }
cTauDevice::cWallMode cTauDevice::getWallMode() { return static_cast<cWallMode>(m_wallMode.load()); }
bool cTauDevice::isLqrWallEngaged() { return m_lqrEngaged.load(); }
double cTauDevice::getLqrPenetration() {
  std::lock_guard<std::mutex> lock(deviceMutex());
  return m_lqr->command().penetration;
}

double cTauDevice::getContactStiffness() {
  std::lock_guard<std::mutex> lock(deviceMutex());
  return m_classifier.stiffness();
}

bool cTauDevice::getContactSurface(cVector3d& a_point, cVector3d& a_normal) {
  std::lock_guard<std::mutex> lock(deviceMutex());
  const uhaptics::SurfaceContact& surface = m_classifier.surface();
  if (!surface.active) return false;
  const uhaptics::Vec3 point = surface.point - m_centre;  // model frame -> device frame
  a_point.set(point.x(), point.y(), point.z());
  a_normal.set(surface.normal.x(), surface.normal.y(), surface.normal.z());
  return true;
}

void cTauDevice::setContactSurface(bool a_active, const cVector3d& a_point, const cVector3d& a_normal) {
  const uhaptics::Vec3 point(a_point(0), a_point(1), a_point(2));
  const uhaptics::Vec3 normal(a_normal(0), a_normal(1), a_normal(2));
  const double length = normal.norm();
  std::lock_guard<std::mutex> lock(deviceMutex());
  m_explicitSurface = true;
  m_explicit.active = a_active && point.allFinite() && std::isfinite(length) && length > 0.0;
  if (m_explicit.active) {
    m_explicit.point = point + m_centre;  // device frame -> model frame
    m_explicit.normal = normal / length;
  }
}

void cTauDevice::clearContactSurface() {
  std::lock_guard<std::mutex> lock(deviceMutex());
  m_explicitSurface = false;
  m_explicit.active = false;
  if (m_classifier.endContact()) sessionStats().count(m_figReleases);
}

std::unique_ptr<uhaptics::BoardPlant> cTauDevice::makeSimulatedPlant() {
  uhaptics::TauBoardPlant::Options options;
  options.hold_tool = false;  // the scripted hand's force is the user
  options.tool_damping = m_toolDamping;
  // The handle's rotational damping (the baseline device's 0.01 N m s/rad, as in tau-study): CHAI3D
  // tools command no torque and the scripted hand holds no orientation, so without it the
  // long-rod platform drifts in orientation under a push until a leg leaves its range.
  options.tool_rotational_damping = m_selection.option("tool_rotational_damping", 0.01, 0.0, 1.0);
  return std::make_unique<uhaptics::TauBoardPlant>(*m_model, options);
}

std::unique_ptr<uhaptics::LqrWallRenderer> cTauDevice::makeWall(int a_delay) const {
  uhaptics::LqrWallRenderer::Options wallOptions;
  wallOptions.keep_direction = true;
  const uhaptics::LqrWallDesign design = uhaptics::designLqrWall(*m_model, m_model->homePose(), {},
                                                                 uhaptics::observerNoiseForDelay(a_delay), a_delay);
  return std::make_unique<uhaptics::LqrWallRenderer>(*m_model, design.gains, wallOptions);
}

void cTauDevice::resetRendering() {
  // Over the board protocol a command acts a period later than on the simulation: the LQR and its
  // observer are designed for the delay the joint I/O has (paper 001's board had none).
  const int delay = commandDelayPeriods();
  if (delay != m_wallDelay) {
    m_lqr = makeWall(delay);
    m_wallDelay = delay;
  }
  m_lqr->reset();
  for (uhaptics::Vec6& sent : m_sent) sent.setZero();
  m_data->pose = m_model->homePose();  // forward kinematics' first guess
  m_classifier.reset();
  m_lqrEngaged = false;
  m_tau.setZero();
}

void cTauDevice::sense(const JointReading& a_reading) noexcept {
  m_q = Eigen::Map<const uhaptics::Vec6>(a_reading.positions);
  m_qd = Eigen::Map<const uhaptics::Vec6>(a_reading.rates);
  m_senseFault = m_model->forward(m_q, *m_data);  // the wall and the scene work from the encoders
  if (m_senseFault != uhaptics::Fault::kNone) return;  // the last assembled state stays
  updateState(*m_data, m_q);
}

void cTauDevice::checkFirstReading() {
  if (m_senseFault != uhaptics::Fault::kNone) {
    throw uhaptics::Error("TAU: the first joint reading does not assemble (forward kinematics fails)");
  }
}

void cTauDevice::readingLost() noexcept {
  m_tau.setZero();
  for (uhaptics::Vec6& sent : m_sent) sent.setZero();  // the device is held at zero meanwhile
  m_lqrEngaged = false;
  m_classifier.holdLost();
}

void cTauDevice::endSession() noexcept {
  m_tau.setZero();
  m_lqrEngaged = false;
  m_classifier.endContact();  // no release counted: the session ends
  m_explicit.active = false;
}

void cTauDevice::recordFigures(const uhaptics::TauContactClassifier::Events& a_events,
                               const uhaptics::Vec3& a_force) noexcept {
  uhaptics::SessionStats& stats = sessionStats();
  if (a_events.engaged) stats.count(m_figEngagements);
  if (a_events.released) stats.count(m_figReleases);
  if (a_events.overload) stats.count(m_figOverloads);
  if (a_events.soft_contact) {
    stats.count(m_figSoftContacts);
    stats.observeMaximum(m_figSoftStiffness, a_events.soft_stiffness);
  }
  if (a_events.held) {
    stats.count(m_figHeldTicks);
    if (a_events.hold_started) stats.observeMaximum(m_figEntryDepth, a_events.entry_depth * 1e3);
    stats.observeMaximum(m_figMaxPenetration, a_events.penetration * 1e3);
    if (a_events.saturated) stats.count(m_figSaturatedTicks);
  } else if (a_force.norm() >= 0.5 * m_classifier.options().contact_force) {
    stats.count(m_figSpringTicks);
  }
}

uhaptics::Fault cTauDevice::render(const ServoInput& a_input, double* a_efforts) noexcept {
  // a_input.dt is the model's servo period (checked equal at construction).
  const uhaptics::TauModel& model = *m_model;
  const uhaptics::Vec3 reported = a_input.seenPosition + m_centre;  // model frame
  uhaptics::Fault fault = m_senseFault;
  if (fault == uhaptics::Fault::kNone) {
    if (m_explicitSurface) {
      m_classifier.follow(m_explicit);
    } else {
      // The application computed its force from the position reported after the previous tick.
      m_classifier.update(a_input.force, reported, classifierMode(m_wallMode.load()));
    }
    // The wall renderer runs every tick: its observer must be settled when a contact begins, and
    // in free space it is the gravity compensation. Its observer is told the torque that acted on
    // the plant over the period the reading ends (m_sent: the application's spring included while
    // the LQR is not engaged), not only its own share, so the spring's force is not mistaken for
    // the user's push.
    const uhaptics::SurfaceContact& surface = m_classifier.surface();
    // sense() solved the forward kinematics of m_q (m_senseFault is kNone): the wall reuses them.
    const uhaptics::WallCommand& wall = m_lqr->tick(m_q, surface, *m_data, &m_sent[m_wallDelay]);
    fault = wall.fault;
    m_tau = wall.torque;
    m_classifier.wallTicked(wall);
    const uhaptics::TauContactClassifier::Events& events = m_classifier.events();
    m_lqrEngaged = m_explicitSurface ? events.held : m_classifier.state() == uhaptics::TauContactClassifier::State::kLqr;
    recordFigures(events, a_input.force);
    if (events.held) {
      if (!m_explicitSurface) {
        // The application's force across the wall's normal (a second face of a concave edge or
        // corner, friction, a mesh's facets): rendered as sent, by the spring.
        const uhaptics::Vec3 across = a_input.force - surface.normal.dot(a_input.force) * surface.normal;
        m_tau.noalias() += m_data->J.topRows<3>().transpose() * across;
        uhaptics::clampSymmetric(m_tau, model.effortLimits());
      }
    } else {
      uhaptics::Vec6 wrench;
      wrench << a_input.force, a_input.torque;
      m_tau.noalias() += m_data->J.transpose() * wrench;  // the application's spring (the baseline)
      uhaptics::scaleIntoBox(m_tau, model.effortLimits());
    }
  }
  if (fault != uhaptics::Fault::kNone || !m_tau.allFinite()) {
    m_tau.setZero();
    m_classifier.holdLost();
    if (fault == uhaptics::Fault::kNone) fault = uhaptics::Fault::kNonFiniteResult;
  }
  for (int i = m_wallDelay; i > 0; --i) m_sent[i] = m_sent[i - 1];
  m_sent[0] = m_tau;
  Eigen::Map<uhaptics::Vec6> out(a_efforts);
  out = m_tau;
  return fault;
}

void cTauDevice::updateState(const uhaptics::TauData& a_data, const uhaptics::Vec6& a_q) noexcept {
  // The pose by forward kinematics (before the first reading: home, at rest); rates through the
  // Jacobian. The angular rates are pose-angle rates; within TAU's +-10 deg they are the angular
  // velocity to within 2 %.
  const uhaptics::Vec6& pose = a_data.pose;
  const uhaptics::Vec6 rates = a_data.J * m_qd;
  m_state.position = pose.head<3>() - m_centre;
  m_state.rotation = uhaptics::PoseRotation(pose).R;
  m_state.linearVelocity = rates.head<3>();
  m_state.angularVelocity = rates.tail<3>();
  m_state.joints = a_q;
}

}  // namespace chai3d
