#include "uhaptics/chai3d/CTauDevice.hpp"

#include <algorithm>
#include <cmath>

#include "uhaptics/core/limits.hpp"
#include "uhaptics/models/tau_kinematics.hpp"
#include "uhaptics/renderers/tau_wall_design.hpp"

namespace chai3d {
namespace {

// Depth the tool must travel into a contact before its stiffness is estimated: four encoder counts
// at the tool (about 0.05 mm each), so quantization does not fake a stiff surface.
constexpr double kProbeDepth = 2e-4;  // m
// Below this force the application's force says nothing about its surface: the session
// statistics' contact threshold, 8 um of depth at 6000 N/m.
constexpr double kTrackForce = 0.05;  // N
// The application force the wall keeps: its plane lies kHoldForce / k under the proxy, so a held
// tool stays inside the application's surface and its force keeps saying where that surface is
// (held on the proxy's own surface, the LQR's integral action would bring that force to zero, and
// the plane could no longer follow). 0.1 mm at 4800 N/m, a tenth of the paper's 1 mm bound; above
// contact_force, so the application's own contact does not flicker; and above the jitter of CHAI3D's
// proxy (its epsilon, 1e-4 world units: 0.6 N at 6000 N/m in a world in device units).
constexpr double kHoldForce = 0.5;  // N
// The normal turns toward the application's force (friction removed) with these gains per new
// force. Along the proxy's path (a surface curving under a sliding proxy): kPathGain, 20 ms, which
// lags a tool sliding at 15 mm/s over a 15 mm radius by 1 deg. Otherwise: kSlowGain, 200 ms, so a
// tool rocking across a concave edge does not swing the wall with it (the faces' forces across the
// wall's normal are rendered by the spring meanwhile) and the proxy's jitter averages out. While
// probing, before the wall holds anything: kProbeGain, 10 ms.
constexpr double kPathGain = 0.05;
constexpr double kSlowGain = 0.005;
constexpr double kProbeGain = 0.1;
// The proxy's path: the chord over this length of it (long against the proxy's jitter, short
// against curvature: the chord of a 15 mm radius is 1 deg off its tangent).
constexpr double kChord = 5e-4;  // m
// The plane's offset along its normal follows the proxy with this gain per new force (5 ms), and
// at most 50 mm/s (twice a brisk hand): a proxy jumping across a mesh's thin feature gives the LQR a
// ramp, not a step.
constexpr double kOffsetGain = 0.2;
constexpr double kPlaneStep = 5e-5;  // m per tick
// While the wall holds the tool and the application feels no contact, the plane sinks this fast
// until it does (past a convex crest the real surface falls away below the plane).
constexpr double kCreepSpeed = 0.01;  // m/s
// The wall's command saturated this long without a break: the device cannot hold the contact
// there; the spring (scaled into the torque limits) takes the contact over.
constexpr int kOverloadTicks = 20;

}  // namespace

cTauDevice::cTauDevice(unsigned int a_deviceNumber, const uhaptics::DeviceSelection& a_selection)
    : cUhapticsDevice(a_deviceNumber, a_selection, 1e-3),
      m_model(std::make_unique<uhaptics::TauModel>(uhaptics::TauModel::load(paramsDirectory() + "/tau.json"))),
      m_stiffThreshold(a_selection.option("stiff_threshold", 3000.0, 1.0, 1e6)),
      m_contactForce(a_selection.option("contact_force", 0.3, 0.01, 10.0)),
      m_releaseTicks(static_cast<int>(std::lround(a_selection.option("release_time", 0.05, 0.001, 1.0) / getServoPeriod()))),
      m_toolDamping(a_selection.option("tool_damping", 0.0, 0.0, 50.0)) {
  const uhaptics::TauModel& model = *m_model;
  if (std::abs(model.servoPeriod() - getServoPeriod()) > 1e-12) {
    throw uhaptics::Error("TAU parameter file: the servo period must be 1 ms (the LQR wall is designed for it)");
  }
  m_wallMode = static_cast<int>(a_selection.option("wall", 0.0, 0.0, 2.0));
  m_centre = model.homePose().head<3>();
  m_data = std::make_unique<uhaptics::TauData>(model);
  // LQR gains at the workspace centre (paper 001 linearizes at one operating point).
  uhaptics::LqrWallRenderer::Options wallOptions;
  wallOptions.keep_direction = true;
  m_lqr = std::make_unique<uhaptics::LqrWallRenderer>(model, uhaptics::designLqrWall(model, model.homePose()).gains, wallOptions);

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
        force = std::min(force, (model.torqueLimit().array() / (J.transpose() * w).array().abs()).minCoeff());
        w.head<3>().setZero();
        w.tail<3>() = u;
        torque = std::min(torque, (model.torqueLimit().array() / (J.transpose() * w).array().abs()).minCoeff());
      }

  setCommonSpecifications("TAU-class 6-DoF parallel device", true);
  m_specifications.m_maxLinearForce = force;
  m_specifications.m_maxAngularTorque = torque;
  m_specifications.m_maxLinearStiffness = 6000.0;  // paper 001's spring-wall baseline
  m_specifications.m_maxAngularStiffness = 1.0;    // assumed: mild rotational springs
  m_specifications.m_maxLinearDamping = 4.0;       // paper 001: Colgate's bound b > K T / 2 for 6000 N/m at 1 kHz
  m_specifications.m_maxAngularDamping = 0.01;     // assumed
  m_specifications.m_workspaceRadius = model.workspaceHalfSide();  // the 50 mm cube's inscribed sphere
  updateState();  // at home until opened

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
  return m_stiffness;
}

bool cTauDevice::getContactSurface(cVector3d& a_point, cVector3d& a_normal) {
  std::lock_guard<std::mutex> lock(deviceMutex());
  if (!m_surface.active) return false;
  const uhaptics::Vec3 point = m_surface.point - m_centre;  // model frame -> device frame
  a_point.set(point.x(), point.y(), point.z());
  a_normal.set(m_surface.normal.x(), m_surface.normal.y(), m_surface.normal.z());
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
  if (m_contact == Contact::kLqr) sessionStats().count(m_figReleases);
  m_contact = Contact::kFree;
  m_held = false;
  m_surface.active = false;
}

void cTauDevice::startBackend() {
  m_lqr->reset();
  m_data->pose = m_model->homePose();  // forward kinematics' first guess
  m_contact = Contact::kFree;
  m_held = false;
  m_surface.active = false;
  m_lastForce.setZero();
  m_framesTicks = 0;
  m_stiffness = 0.0;
  m_lqrEngaged = false;
  m_tau.setZero();
  m_qd.setZero();
  m_rate.reset();
  if (hasBoard()) {
    m_sim.reset();
    startBoard(6, 6, m_q.data());
    if (m_model->forward(m_q, *m_data) != uhaptics::Fault::kNone) {
      throw uhaptics::Error("TAU: the board's first joint reading does not assemble (forward kinematics fails)");
    }
  } else {
    uhaptics::SimulatedTauOptions options;
    options.tool_damping = m_toolDamping;
    // The handle's rotational damping (the baseline device's 0.01 N m s/rad, as in tau-study): CHAI3D
    // tools command no torque and the scripted hand holds no orientation, so without it the
    // long-rod platform drifts in orientation under a push until a leg leaves its range.
    options.tool_rotational_damping = m_selection.option("tool_rotational_damping", 0.01, 0.0, 1.0);
    m_sim = std::make_unique<uhaptics::SimulatedTau>(*m_model, options);
    m_sim->reset(m_model->homeJoints());
    m_sim->detachHand();  // the scripted hand's force arrives as the external force
    m_q = m_sim->encoderReading();
  }
  updateState();
}

void cTauDevice::stopBackend() noexcept {
  m_tau.setZero();
  m_lqrEngaged = false;
  m_held = false;
  m_contact = Contact::kFree;
  m_surface.active = false;
  m_explicit.active = false;
}

void cTauDevice::release() noexcept {
  if (m_contact == Contact::kLqr) sessionStats().count(m_figReleases);
  m_contact = Contact::kFree;
  m_surface.active = false;
}

double cTauDevice::perTick(double a_gain) const noexcept {
  // The filters' gains are per servo tick; an application slower than the servo sends a new force
  // every few ticks, and each then counts for all of them (time constants in time, not in frames).
  return m_framesTicks <= 1 ? a_gain : 1.0 - std::pow(1.0 - a_gain, std::min(m_framesTicks, 50));
}

void cTauDevice::trackSurface(const uhaptics::Vec3& a_force, const uhaptics::Vec3& a_position, double a_stiffness,
                              double a_turnGain) noexcept {
  // A force below kTrackForce, or one pointing into the surface (proxy jitter), is no evidence.
  const double magnitude = a_force.norm();
  if (!(magnitude >= kTrackForce) || !(a_force.dot(m_normal) > 0.0)) {
    m_hasProxy = false;
    return;
  }
  // The application's proxy: its force is F = k (proxy - tool).
  m_proxy = a_position + a_force / a_stiffness;
  m_hasProxy = true;
  m_trailHead = (m_trailHead + 1) % kTrailLength;
  m_trail[m_trailHead] = m_proxy;
  m_trailCount = std::min(m_trailCount + 1, kTrailLength);
  // The proxy's path: the chord back to where it was kChord ago, if that is in the trail (a proxy
  // that moved less is stuck by static friction, or stopped in a concave edge).
  uhaptics::Vec3 path = uhaptics::Vec3::Zero();
  for (int i = 1; i < m_trailCount; ++i) {
    const uhaptics::Vec3 travel = m_proxy - m_trail[(m_trailHead + kTrailLength - i) % kTrailLength];
    const double length = travel.norm();
    if (length >= kChord) {
      path = travel / length;
      break;
    }
  }
  // Friction: CHAI3D's finger proxy, slipping, sits on its friction cone's rim on the way to the
  // tool, so its tangential force points against its own motion, which lies in the surface (normal
  // to it). F's component along the path is that friction and is removed; what is left is normal to
  // the path, as the surface normal is. A stuck proxy's F is tilted by at most atan(mu_s), and only
  // the slow gain turns the normal toward it.
  const uhaptics::Vec3 normalForce = a_force - a_force.dot(path) * path;
  const double length = normalForce.norm();
  if (!(length > 0.0)) return;
  const uhaptics::Vec3 turn = normalForce / length - m_normal;
  const uhaptics::Vec3 alongPath = turn.dot(path) * path;  // = -(n . path) path: geometry, not F
  const double weight = std::min(1.0, length / kHoldForce);  // a small force counts in proportion
  const uhaptics::Vec3 normal = m_normal + perTick(kPathGain) * alongPath + weight * perTick(a_turnGain) * (turn - alongPath);
  const double norm = normal.norm();
  if (norm > 1e-9 && std::isfinite(norm)) m_normal = normal / norm;
}

void cTauDevice::startContact(const uhaptics::Vec3& a_force, int a_mode) noexcept {
  m_contact = a_mode == C_TAU_WALL_SPRING ? Contact::kSpring : Contact::kProbing;
  m_normal = a_force.normalized();
  m_hasProxy = false;
  m_trailCount = 0;
  m_probeForce = 0.0;
  m_probeDepth = 0.0;
  m_quietTicks = 0;
}

void cTauDevice::updateContact(const uhaptics::Vec3& a_force, const uhaptics::Vec3& a_position) noexcept {
  const double magnitude = a_force.norm();
  const int mode = m_wallMode.load();
  // A force the application has not sent before was computed from the position it read last (the
  // one reported after the previous tick); a repeated one is older and says nothing new.
  const bool fresh = (a_force.array() != m_lastForce.array()).any();
  // Servo ticks since the last new force, this one included, counted while that force was a
  // contact (a force that stayed zero held no information to wait for).
  m_framesTicks = m_lastForce.norm() >= kTrackForce ? m_framesTicks + 1 : 1;

  if (m_contact == Contact::kFree) {
    if (magnitude > m_contactForce && std::isfinite(magnitude)) startContact(a_force, mode);
  } else {
    if (mode == C_TAU_WALL_SPRING && m_contact != Contact::kSpring) {
      release();  // switched to the spring mid-contact
      m_contact = Contact::kSpring;
    }
    // Out of contact: the wall does not hold the tool and the application feels (almost) nothing;
    // or the wall holds it where the application feels nothing at all (a plane above its surface).
    const bool out = m_held ? magnitude < kTrackForce : magnitude < 0.5 * m_contactForce;
    m_quietTicks = out ? m_quietTicks + 1 : 0;
    if (m_quietTicks >= m_releaseTicks) {
      release();
    } else if (m_contact == Contact::kLqr && m_overloadTicks >= kOverloadTicks) {
      release();
      m_contact = Contact::kSpring;
      sessionStats().count(m_figOverloads);
    } else if (m_contact == Contact::kProbing && fresh) {
      // Stiffness along the normal: force rise over depth, summed over new forces (a tool sliding
      // over a curved surface at constant depth adds nothing to either, where a secant from the
      // onset would count the surface's curvature as depth). The proxy is placed with the device's
      // nominal stiffness until the probe has measured the scene's.
      trackSurface(a_force, a_position, m_specifications.m_maxLinearStiffness, kProbeGain);
      m_probeForce += m_normal.dot(a_force - m_lastForce);
      m_probeDepth += m_normal.dot(m_lastPosition - a_position);
      if (m_probeDepth >= kProbeDepth) {
        const double k = m_probeForce / m_probeDepth;
        m_stiffness = std::isfinite(k) ? std::max(0.0, k) : 0.0;
        if (m_stiffness > 0.0 && (m_stiffness >= m_stiffThreshold || mode == C_TAU_WALL_LQR)) {
          m_contact = Contact::kLqr;
          m_overloadTicks = 0;
          m_surface.active = true;
          m_surface.normal = m_normal;
          m_surface.point = a_position + (a_force - kHoldForce * m_normal) / m_stiffness;
          sessionStats().count(m_figEngagements);
        } else {
          m_contact = Contact::kSpring;  // a soft surface: the spring renders the whole contact
          sessionStats().count(m_figSoftContacts);
          sessionStats().observeMaximum(m_figSoftStiffness, m_stiffness);
        }
      }
    } else if (m_contact == Contact::kLqr) {
      // The plane: kHoldForce / k under the proxy, normal to the tracked normal; held without any
      // force from the application, it sinks.
      uhaptics::Vec3 step = uhaptics::Vec3::Zero();
      double gain = 1.0;
      if (fresh) trackSurface(a_force, a_position, m_stiffness, kSlowGain);
      if (fresh && m_hasProxy) {
        step = m_proxy - (kHoldForce / m_stiffness) * m_normal - m_surface.point;
        gain = perTick(kOffsetGain);
      } else if (m_held && magnitude < kTrackForce) {
        step = -kCreepSpeed * getServoPeriod() * m_normal;
      }
      const double along = m_normal.dot(step);
      const double most = kPlaneStep * std::max(1, std::min(m_framesTicks, 50));  // 50 mm/s
      step += (std::min(most, std::max(-most, gain * along)) - along) * m_normal;
      m_surface.point += step;
      m_surface.normal = m_normal;
    }
  }
  if (fresh) {
    m_lastForce = a_force;
    m_lastPosition = a_position;
    m_framesTicks = 0;
  }
}

uhaptics::Fault cTauDevice::servoTick(const ServoInput& a_input, double& a_outputMagnitude) noexcept {
  // a_input.dt is the model's servo period (checked equal at construction).
  const uhaptics::TauModel& model = *m_model;
  const uhaptics::Vec3 reported = m_state.position + m_centre;  // model frame
  a_outputMagnitude = 0.0;
  if (hasBoard()) {
    std::uint32_t sample_us = 0;
    if (!readBoard(m_q.data(), sample_us)) {  // zero commanded: link down or host watchdog
      m_tau.setZero();
      m_lqrEngaged = false;
      m_held = false;
      return uhaptics::Fault::kDeviceError;
    }
    m_rate.update(m_q.data(), 6, sample_us, m_qd.data());
  } else {
    m_q = m_sim->encoderReading();
  }
  uhaptics::Fault fault = model.forward(m_q, *m_data);
  if (fault == uhaptics::Fault::kNone) {
    if (m_explicitSurface) {
      const bool was = m_contact == Contact::kLqr;
      m_surface = m_explicit;
      m_contact = m_surface.active ? Contact::kLqr : Contact::kFree;
      if (m_surface.active && !was) sessionStats().count(m_figEngagements);
      if (!m_surface.active && was) sessionStats().count(m_figReleases);
    } else {
      // The application computed its force from the position reported after the previous tick.
      updateContact(a_input.force, reported);
      if (m_contact != Contact::kLqr) m_surface.active = false;
    }
    // The wall renderer runs every tick: its observer must be settled when a contact begins, and
    // in free space it is the gravity compensation. Its observer is told the torque the device was
    // last commanded (m_tau, the application's spring included while the LQR is not engaged), not
    // only its own share, so the spring's force is not mistaken for the user's push.
    const uhaptics::WallCommand& wall = m_lqr->tick(m_q, m_surface, &m_data->pose, &m_tau);
    fault = wall.fault;
    m_tau = wall.torque;
    const bool was_held = m_held;
    m_held = m_contact == Contact::kLqr && wall.in_contact;
    m_lqrEngaged = m_explicitSurface ? m_held : m_contact == Contact::kLqr;
    m_overloadTicks = m_held && wall.saturated ? m_overloadTicks + 1 : 0;
    if (m_held) {
      uhaptics::SessionStats& stats = sessionStats();
      stats.count(m_figHeldTicks);
      if (!was_held) {
        m_entryDepth = wall.penetration;
        stats.observeMaximum(m_figEntryDepth, wall.penetration * 1e3);
      }
      if (wall.penetration <= kSettledDepth) m_entryDepth = 0.0;
      stats.observeMaximum(m_figMaxPenetration, std::max(0.0, wall.penetration - m_entryDepth) * 1e3);
      if (wall.saturated) stats.count(m_figSaturatedTicks);
      if (!m_explicitSurface) {
        // The application's force across the wall's normal (a second face of a concave edge or
        // corner, friction, a mesh's facets): rendered as sent, by the spring.
        const uhaptics::Vec3 across = a_input.force - m_surface.normal.dot(a_input.force) * m_surface.normal;
        m_tau.noalias() += m_data->J.topRows<3>().transpose() * across;
        uhaptics::clampSymmetric(m_tau, model.torqueLimit());
      }
    } else {
      uhaptics::Vec6 wrench;
      wrench << a_input.force, a_input.torque;
      m_tau.noalias() += m_data->J.transpose() * wrench;  // the application's spring (the baseline)
      uhaptics::scaleIntoBox(m_tau, model.torqueLimit());
      if (a_input.force.norm() >= 0.5 * m_contactForce) sessionStats().count(m_figSpringTicks);
    }
  }
  if (fault != uhaptics::Fault::kNone || !m_tau.allFinite()) {
    m_tau.setZero();
    m_held = false;
    if (fault == uhaptics::Fault::kNone) fault = uhaptics::Fault::kNonFiniteResult;
  }
  uhaptics::Fault backend_fault = uhaptics::Fault::kNone;
  if (hasBoard()) {
    commandBoard(m_tau.data());
  } else {
    backend_fault = m_sim->step(m_tau, a_input.handForce);
  }
  a_outputMagnitude = m_tau.cwiseAbs().maxCoeff();
  updateState();
  return fault != uhaptics::Fault::kNone ? fault : backend_fault;
}

void cTauDevice::updateState() noexcept {
  if (hasBoard()) {  // the board's reading: pose by forward kinematics, rates by the joints' differences
    const uhaptics::Vec6& pose = m_data->pose;
    const uhaptics::Vec6 rates = m_data->J * m_qd;
    m_state.position = pose.head<3>() - m_centre;
    m_state.rotation = uhaptics::PoseRotation(pose).R;
    m_state.linearVelocity = rates.head<3>();
    m_state.angularVelocity = rates.tail<3>();  // pose-angle rates, see below
    m_state.joints = m_q;
    return;
  }
  if (!m_sim) {  // before the first open(): at home, at rest
    m_state.position = m_model->homePose().head<3>() - m_centre;
    m_state.joints = m_model->homeJoints();
    return;
  }
  const uhaptics::Vec6& pose = m_sim->pose();
  m_state.position = pose.head<3>() - m_centre;
  m_state.rotation = uhaptics::PoseRotation(pose).R;
  m_state.linearVelocity = m_sim->toolVelocity();
  // Pose-angle rates; within TAU's +-10 deg they are the angular velocity to within 2 %.
  m_state.angularVelocity = (m_data->J * m_sim->qd()).tail<3>();
  m_state.joints = m_sim->q();
}

}  // namespace chai3d
