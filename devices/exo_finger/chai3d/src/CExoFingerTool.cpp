#include "uhaptics/chai3d/CExoFingerTool.hpp"

#include <cmath>
#include <string>

#include "uhaptics/chai3d/vector_conversions.hpp"
#include "uhaptics/core/fault.hpp"
#include "uhaptics/core/regularized_solve.hpp"

namespace chai3d {
namespace {

constexpr cExoFingerTool::cPhalanxPoint kFingertip{cExoFingerTool::C_PHALANX_MIDDLE, 1.0};

uhaptics::Vec2 unit(double a_angle) { return uhaptics::Vec2(std::cos(a_angle), std::sin(a_angle)); }
uhaptics::Vec2 unitDerivative(double a_angle) { return uhaptics::Vec2(-std::sin(a_angle), std::cos(a_angle)); }

}  // namespace

std::vector<cExoFingerTool::cPhalanxPoint> cExoFingerTool::defaultPoints() {
  return {{C_PHALANX_PROXIMAL, 1.0 / 3.0}, {C_PHALANX_PROXIMAL, 2.0 / 3.0}, {C_PHALANX_PROXIMAL, 1.0},
          {C_PHALANX_MIDDLE, 1.0 / 3.0},   {C_PHALANX_MIDDLE, 2.0 / 3.0},   {C_PHALANX_MIDDLE, 1.0}};
}

cExoFingerTool::cExoFingerTool(cWorld* a_parentWorld, const std::vector<cPhalanxPoint>& a_points)
    : cGenericTool(a_parentWorld), m_fingerColor(0.9f, 0.75f, 0.6f), m_points(a_points) {
  if (m_points.empty()) throw uhaptics::Error("cExoFingerTool: at least one phalanx point is needed");
  for (const cPhalanxPoint& p : m_points) {
    if (!(p.m_fraction >= 0.0 && p.m_fraction <= 1.0) ||
        (p.m_phalanx != C_PHALANX_PROXIMAL && p.m_phalanx != C_PHALANX_MIDDLE)) {
      throw uhaptics::Error("cExoFingerTool: a phalanx point must be on the proximal or middle phalanx, at a "
                            "fraction in [0, 1] of its length (got " + std::to_string(p.m_fraction) + ")");
    }
    cHapticPoint* point = new cHapticPoint(this);
    addComponent(point->m_sphereGoal);
    addComponent(point->m_sphereProxy);
    m_hapticPoints.push_back(point);
  }
  m_pointGlobalPos.assign(m_points.size(), cVector3d(0, 0, 0));
  m_pointGlobalVel.assign(m_points.size(), cVector3d(0, 0, 0));
  m_pointGlobalForce.assign(m_points.size(), cVector3d(0, 0, 0));
  setShowContactPoints(true, false);
}

cExoFingerTool::~cExoFingerTool() {
  for (cHapticPoint* point : m_hapticPoints) {
    // The spheres are components of this object (deleted with it) and owned by the point too:
    // detach them so each is deleted once, by the point.
    removeComponent(point->m_sphereGoal);
    removeComponent(point->m_sphereProxy);
    delete point;
  }
}

void cExoFingerTool::setExoFingerDevice(const cExoFingerDevicePtr& a_device) {
  if (a_device == nullptr) return;
  m_exo = a_device;
  setHapticDevice(a_device);
  const uhaptics::ExoFingerGeometry& g = a_device->getModel().geometry();
  m_proximalLength = g.proximal_length;
  m_middleLength = g.middle_length;
}

uhaptics::Vec3 cExoFingerTool::position(const cPhalanxPoint& a_point, const uhaptics::Vec2& a_x) const {
  const bool middle = a_point.m_phalanx == C_PHALANX_MIDDLE;
  uhaptics::Vec2 hand = (middle ? 1.0 : a_point.m_fraction) * m_proximalLength * unit(a_x(0));
  if (middle) hand += a_point.m_fraction * m_middleLength * unit(a_x(0) + a_x(1));
  return m_exo->handToDevice(hand);
}

uhaptics::Mat<3, 2> cExoFingerTool::jacobian(const cPhalanxPoint& a_point, const uhaptics::Vec2& a_x) const {
  const bool middle = a_point.m_phalanx == C_PHALANX_MIDDLE;
  // Hand frame: d p / d q_MCP turns the whole chain; d p / d q_PIP only the middle phalanx.
  uhaptics::Mat2 J = uhaptics::Mat2::Zero();
  J.col(0) = (middle ? 1.0 : a_point.m_fraction) * m_proximalLength * unitDerivative(a_x(0));
  if (middle) {
    J.col(1) = a_point.m_fraction * m_middleLength * unitDerivative(a_x(0) + a_x(1));
    J.col(0) += J.col(1);
  }
  // The device frame is an affine image of the hand frame: map directions by differences.
  const uhaptics::Vec3 origin = m_exo->handToDevice(uhaptics::Vec2::Zero());
  uhaptics::Mat<3, 2> Jd;
  Jd.col(0) = m_exo->handToDevice(J.col(0)) - origin;
  Jd.col(1) = m_exo->handToDevice(J.col(1)) - origin;
  return Jd;
}

cVector3d cExoFingerTool::toGlobal(const uhaptics::Vec3& a_devicePoint) const {
  return m_globalPos + m_globalRot * (m_workspaceScaleFactor * toChai(a_devicePoint));
}

void cExoFingerTool::initialize() {
  updateFromDevice();
  for (size_t i = 0; i < m_hapticPoints.size(); ++i) m_hapticPoints[i]->initialize(m_pointGlobalPos[i]);
}

void cExoFingerTool::updateFromDevice() {
  cGenericTool::updateFromDevice();  // fingertip pose, velocities, switches (and the enabled check)
  if (m_exo == nullptr || !m_enabled) return;
  m_fingerAngles = m_exo->getFingerAngles();
  // Joint rates from the fingertip velocity (the device differentiates its fingertip position);
  // damped near the straight finger, where the tip cannot tell MCP from PIP motion. Only the
  // potential-field effects (viscosity) use the points' velocities.
  const uhaptics::Vec2 rates = uhaptics::regularizedSolve(jacobian(kFingertip, m_fingerAngles),
                                                          toEigen(m_deviceLocalLinVel / m_workspaceScaleFactor));
  for (size_t i = 0; i < m_points.size(); ++i) {
    m_pointGlobalPos[i] = toGlobal(position(m_points[i], m_fingerAngles));
    const uhaptics::Vec3 velocity = jacobian(m_points[i], m_fingerAngles) * rates;
    m_pointGlobalVel[i] = m_globalRot * (m_workspaceScaleFactor * toChai(velocity));
  }
}

void cExoFingerTool::computeInteractionForces() {
  cVector3d total(0, 0, 0);
  m_jointTorque.setZero();
  const cMatrix3d toDevice = cTranspose(m_globalRot);
  for (size_t i = 0; i < m_hapticPoints.size(); ++i) {
    const cVector3d force = m_hapticPoints[i]->computeInteractionForces(m_pointGlobalPos[i], m_deviceGlobalRot,
                                                                        m_pointGlobalVel[i], m_deviceGlobalAngVel);
    m_pointGlobalForce[i] = force;
    total.add(force);
    if (m_exo != nullptr && !force.equals(cVector3d(0, 0, 0))) {
      m_jointTorque.noalias() += jacobian(m_points[i], m_fingerAngles).transpose() * toEigen(toDevice * force);
    }
  }
  setDeviceGlobalForce(total);  // for display and the small-force start-up check
  setDeviceGlobalTorque(cVector3d(0, 0, 0));
  setGripperForce(0.0);
}

bool cExoFingerTool::applyToDevice() {
  if (m_exo == nullptr || !m_enabled) return C_ERROR;
  // CHAI3D's start-up rules, step for step as cGenericTool::applyToDevice (CHAI3D 3.3) applies them
  // to a Cartesian force, here to the joint torque, which is this tool's whole command.
  uhaptics::Vec2 torque = m_jointTorque;

  // Wait for small force: forces engage once the tool's force stayed below the threshold for more
  // than three frames.
  if (!m_forceEngaged) {
    if (!m_useWaitForSmallForce) {
      m_forceEngaged = true;
    } else if (m_deviceLocalForce.length() < m_smallForceThresh) {
      if (m_smallForceCounter > 3) {
        m_forceEngaged = true;
        m_smallForceCounter = 0;
      } else {
        ++m_smallForceCounter;
      }
    } else {
      m_smallForceCounter = 0;
    }
  }

  // Force rise: from engagement, the command is scaled by t / rise time (wall clock) until the
  // rise time has passed. As in CHAI3D, without setUseForceRise(true) the rise is switched off on
  // the first engaged frame, whose scale is that of the unstarted clock (0: one zero frame).
  if (m_forceEngaged && m_flagForceRiseActivated) {
    if (m_flagForceRiseFirstTime) {
      if (m_useForceRise) {
        m_forceRiseClock.reset();
        m_forceRiseClock.start();
        m_flagForceRiseFirstTime = false;
      } else {
        m_flagForceRiseActivated = false;
      }
    }
    double scale = 1.0;
    const double time = cClamp(m_forceRiseClock.getCurrentTimeSeconds(), 0.0, m_forceRiseTime);
    if (m_forceRiseTime > C_SMALL) {
      scale = time / m_forceRiseTime;
      torque *= scale;
    }
    // CHAI3D's rising damping, (1 - scale) 0.2 of the device's linear damping on the tool's
    // velocity when both loops run above 400 Hz, as a fingertip force mapped to the finger joints.
    // The exoskeleton specifies no damping (a position-driven finger), so it adds nothing there.
    // (The specification is read in place: getSpecifications() copies its strings, an allocation.)
    const double kMinFrequency = 400.0;
    const double damping = (1.0 - scale) * 0.2 * m_exo->m_specifications.m_maxLinearDamping;
    if (damping > 0.0 && m_freqRead.getFrequency() > kMinFrequency && m_freqWrite.getFrequency() > kMinFrequency) {
      torque.noalias() -= damping * (jacobian(kFingertip, m_fingerAngles).transpose() * toEigen(m_deviceLocalLinVel));
    }
    if (m_forceRiseClock.getCurrentTimeSeconds() >= m_forceRiseTime) m_flagForceRiseActivated = false;
  }

  const bool on = m_forceOn && m_forceEngaged;
  m_exo->setFingerJointTorque(on ? torque : uhaptics::Vec2::Zero());
  m_freqWrite.signal(1);
  // The Cartesian channel stays zero: the whole command is the joint torque above. This call is
  // what advances the device's servo ticks.
  return m_exo->setForceAndTorqueAndGripperForce(cVector3d(0, 0, 0), cVector3d(0, 0, 0), 0.0);
}

void cExoFingerTool::render(cRenderOptions& a_options) {
  for (cHapticPoint* point : m_hapticPoints) point->render(a_options);
#ifdef C_USE_OPENGL
  if (m_exo == nullptr || !SECTION_RENDER_OPAQUE_PARTS_ONLY(a_options)) return;
  // The virtual finger: MCP -> PIP -> fingertip, in tool coordinates.
  const uhaptics::Vec2 x = m_fingerAngles;
  const uhaptics::Vec2 pip = m_proximalLength * unit(x(0));
  const uhaptics::Vec2 tip = pip + m_middleLength * unit(x(0) + x(1));
  const cVector3d joints[3] = {m_workspaceScaleFactor * toChai(m_exo->handToDevice(uhaptics::Vec2::Zero())),
                               m_workspaceScaleFactor * toChai(m_exo->handToDevice(pip)),
                               m_workspaceScaleFactor * toChai(m_exo->handToDevice(tip))};
  glDisable(GL_LIGHTING);
  glLineWidth(6.0f);
  m_fingerColor.render();
  glBegin(GL_LINE_STRIP);
  for (const cVector3d& p : joints) glVertex3d(p(0), p(1), p(2));
  glEnd();
  glLineWidth(1.0f);
  glEnable(GL_LIGHTING);
#else
  (void)a_options;
#endif
}

}  // namespace chai3d
