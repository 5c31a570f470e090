#pragma once
// chai3d::cAlgorithmLqrWall: CHAI3D's finger-proxy algorithm with paper 001's LQR wall behind it,
// for applications that want the LQR wall explicitly instead of cTauDevice reading the surface from
// the force.
//
// It is the finger proxy (same constraints, friction, force) plus one step: after each proxy
// update, the contact -- the proxy centre as the surface point and the constraint's normal (from
// the goal to the proxy, or the collision event's normal when they coincide) -- goes to the TAU
// device (cTauDevice::setContactSurface), whose servo loop then holds the tool on that plane with
// the LQR position-control wall at 1 kHz. The finger proxy's spring force is still returned (it is
// what the tool shows and what the device renders before the wall engages and after it releases).
//
// Near the surface the proxy may report no contact while the wall holds the tool exactly on it;
// the last surface is kept while the tool stays within `release_distance` above it, so contact
// does not chatter; the wall itself releases when the tool leaves (LqrWallRenderer::Options).
//
// Install it into a haptic point (it replaces, and deletes, that point's finger proxy):
//   auto* wall = cAlgorithmLqrWall::install(tool->getHapticPoint(0), tauDevice);
//   wall->setEnabled(false);   // back to the plain spring (the device's own wall mode), e.g. a key
#include "uhaptics/chai3d/CTauDevice.hpp"  // first: CHAI3D's feature switches
#include "forces/CAlgorithmFingerProxy.h"
#include "tools/CHapticPoint.h"

namespace chai3d {

class cAlgorithmLqrWall : public cAlgorithmFingerProxy {
 public:
  /// a_tool: the tool whose frame maps world to device coordinates (the haptic point's parent).
  /// Throws uhaptics::Error when either is null.
  cAlgorithmLqrWall(cGenericTool* a_tool, const cTauDevicePtr& a_device);
  virtual ~cAlgorithmLqrWall();

  /// Replaces a_point's finger-proxy algorithm (radius and settings carried over) and returns the
  /// new algorithm, owned by the point. Throws uhaptics::Error on a null point or device.
  static cAlgorithmLqrWall* install(cHapticPoint* a_point, const cTauDevicePtr& a_device);

  virtual cVector3d computeForces(const cVector3d& a_toolPos, const cVector3d& a_toolVel);

  /// Off: the device gets no surface and renders the spring (or its own wall mode).
  void setEnabled(bool a_enabled);
  bool getEnabled() const { return m_enabled; }
  /// Hysteresis above the last surface before it is dropped [m] (default 0.5 mm, 10 encoder counts).
  void setReleaseDistance(double a_distance) { m_releaseDistance = cAbs(a_distance); }

  /// The surface last sent (world coordinates) and whether it is active.
  bool isSurfaceActive() const { return m_active; }
  cVector3d getSurfacePoint() const { return m_point; }
  cVector3d getSurfaceNormal() const { return m_normal; }

 private:
  void sendSurface();

  cGenericTool* m_tool;
  cTauDevicePtr m_device;
  bool m_enabled = true;
  bool m_active = false;
  double m_releaseDistance = 5e-4;
  cVector3d m_point, m_normal;
};

}  // namespace chai3d
