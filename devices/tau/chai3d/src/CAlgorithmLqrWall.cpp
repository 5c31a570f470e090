#include "uhaptics/chai3d/CAlgorithmLqrWall.hpp"

#include "math/CMaths.h"
#include "tools/CGenericTool.h"
#include "uhaptics/core/fault.hpp"

namespace chai3d {

cAlgorithmLqrWall::cAlgorithmLqrWall(cGenericTool* a_tool, const cTauDevicePtr& a_device)
    : m_tool(a_tool), m_device(a_device), m_point(0, 0, 0), m_normal(0, 0, 1) {
  if (m_tool == nullptr || m_device == nullptr) throw uhaptics::Error("cAlgorithmLqrWall needs a tool and a TAU device");
}

cAlgorithmLqrWall::~cAlgorithmLqrWall() {
  if (m_enabled) m_device->clearContactSurface();
}

cAlgorithmLqrWall* cAlgorithmLqrWall::install(cHapticPoint* a_point, const cTauDevicePtr& a_device) {
  if (a_point == nullptr) throw uhaptics::Error("cAlgorithmLqrWall::install: no haptic point");
  cAlgorithmFingerProxy* previous = a_point->m_algorithmFingerProxy;
  auto* wall = new cAlgorithmLqrWall(a_point->getParentTool(), a_device);
  // Same proxy: geometry, collision and friction settings, and state.
  wall->m_collisionSettings = previous->m_collisionSettings;
  wall->setProxyRadius(previous->getProxyRadius());
  wall->m_useDynamicProxy = previous->m_useDynamicProxy;
  wall->m_frictionDynHysteresisMultiplier = previous->m_frictionDynHysteresisMultiplier;
  wall->m_forceShadingAngleThreshold = previous->m_forceShadingAngleThreshold;
  wall->setEpsilonBaseValue(previous->getEpsilonBaseValue());
  wall->setShowEnabled(previous->getShowEnabled());
  if (previous->getWorld() != nullptr) wall->initialize(previous->getWorld(), previous->getProxyGlobalPosition());
  a_point->m_algorithmFingerProxy = wall;
  delete previous;
  return wall;
}

void cAlgorithmLqrWall::setEnabled(bool a_enabled) {
  if (a_enabled == m_enabled) return;
  m_enabled = a_enabled;
  m_active = false;
  if (!m_enabled) m_device->clearContactSurface();
}

cVector3d cAlgorithmLqrWall::computeForces(const cVector3d& a_toolPos, const cVector3d& a_toolVel) {
  const cVector3d force = cAlgorithmFingerProxy::computeForces(a_toolPos, a_toolVel);
  if (!m_enabled) return force;
  const cVector3d pull = m_proxyGlobalPos - m_deviceGlobalPos;  // goal -> proxy: out of the surface
  if (m_numCollisionEvents > 0) {
    m_active = true;
    m_point = m_proxyGlobalPos;
    // The surface normal: the touched triangles' (summed over the proxy's constraints, so an edge
    // or corner gets the mean of its faces). Not the goal-to-proxy direction: with friction the
    // proxy sticks while the goal slides below it, tilting that direction off the surface.
    cVector3d faces(0, 0, 0);
    for (unsigned int i = 0; i < m_numCollisionEvents; ++i) faces.add(m_collisionEvents[i]->m_globalNormal);
    const double length = faces.length();
    if (length > 0.0) m_normal = faces / length;
    else if (pull.length() > 0.0) m_normal = cNormalize(pull);
  } else if (m_active && cDot(m_normal, m_deviceGlobalPos - m_point) > m_releaseDistance) {
    m_active = false;  // the tool left the surface (beyond the hysteresis)
  }
  sendSurface();
  return force;
}

void cAlgorithmLqrWall::sendSurface() {
  // World -> device frame: the inverse of the tool's map (global = pos + R scale device).
  const cMatrix3d toDevice = cTranspose(m_tool->getGlobalRot());
  const double scale = m_tool->getWorkspaceScaleFactor();
  const cVector3d point = toDevice * (m_point - m_tool->getGlobalPos()) / scale;
  m_device->setContactSurface(m_active, point, toDevice * m_normal);
}

}  // namespace chai3d
