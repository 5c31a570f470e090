#pragma once
// chai3d::cExoFingerTool: a multi-point CHAI3D tool for the finger exoskeleton (paper 000's setting:
// the virtual finger is touched along its phalanges, not only at the fingertip).
//
// Each point sits on a phalanx of the virtual finger (proximal or middle, at a fraction of its
// length from the joint it hangs on) and is a stock cHapticPoint with CHAI3D's finger-proxy
// algorithm, so every point finds its own contacts in the scene. Per haptic frame:
//
//   p_i = f_i(x)                     point i on the virtual finger x = (q_MCP, q_PIP), device frame
//   F_i = k (proxy_i - p_i)          the point's proxy force (CHAI3D's finger proxy), device frame
//   tau_x = sum_i J_i(x)^T F_i       J_i = d p_i / d x: the stacked proxy displacements as
//                                    virtual-finger joint torques
//
// tau_x goes to the device (cExoFingerDevice::setFingerJointTorque), whose subspace-proxy renderer
// reads it as the joint-space proxy x_p = x + Z_x^-1 tau_x and displays only what the actuated
// subspace can (eq. 6): a contact on the proximal phalanx gives no PIP torque, one on the middle
// phalanx loads both joints, and the actuator shows their projection.
//
// CHAI3D's start-up rules of cGenericTool apply to tau_x as they apply to a stock tool's force:
// setWaitForSmallForce() holds it back until the tool's force stayed small, setUseForceRise() /
// setRiseTime() ramp it up from engagement (and after setForcesON()), setForcesOFF() zeroes it.
//
// On a device from CHAI3D's cHapticDeviceHandler (the uhaptics slot), attach the exoskeleton behind
// it: setExoFingerDevice(std::dynamic_pointer_cast<cExoFingerDevice>(
//     uhaptics::adapter::uhapticsDevice(hapticDevice)))   (uhaptics/chai3d/device_registry.hpp).
//
// The tool frame is the device frame scaled by the workspace scale factor (as for any CHAI3D tool);
// point forces are mapped back like CHAI3D's cToolCursor does (rotation only, no scaling).
// Servo use: updateFromDevice(), computeInteractionForces(), applyToDevice() allocate nothing.
#include <vector>

#include "uhaptics/chai3d/CExoFingerDevice.hpp"  // first: CHAI3D's feature switches
#include "tools/CGenericTool.h"
#include "tools/CHapticPoint.h"

namespace chai3d {

class cExoFingerTool : public cGenericTool {
 public:
  enum cPhalanx { C_PHALANX_PROXIMAL = 0, C_PHALANX_MIDDLE = 1 };
  /// A point on a phalanx: a_fraction in [0, 1] of its length from the joint it hangs on.
  struct cPhalanxPoint {
    cPhalanx m_phalanx;
    double m_fraction;
  };
  /// Three points per phalanx at 1/3, 2/3 and the end (the fingertip is the last one).
  static std::vector<cPhalanxPoint> defaultPoints();

  /// Throws uhaptics::Error if a point is not on a phalanx (fraction outside [0, 1]) or none is given.
  explicit cExoFingerTool(cWorld* a_parentWorld, const std::vector<cPhalanxPoint>& a_points = defaultPoints());
  virtual ~cExoFingerTool();
  virtual std::string getClassName() { return "ExoFingerTool"; }

  /// The tool needs the exoskeleton's finger state: use this instead of setHapticDevice().
  void setExoFingerDevice(const cExoFingerDevicePtr& a_device);
  cExoFingerDevicePtr getExoFingerDevice() const { return m_exo; }

  virtual void initialize();
  virtual void updateFromDevice();
  virtual void computeInteractionForces();
  virtual bool applyToDevice();
  virtual void render(cRenderOptions& a_options);

  const cPhalanxPoint& getPhalanxPoint(int a_index) const { return m_points[static_cast<size_t>(a_index)]; }
  /// Point a_index in world coordinates (its goal, where the finger is) and its last proxy force [N].
  cVector3d getPointGlobalPos(int a_index) const { return m_pointGlobalPos[static_cast<size_t>(a_index)]; }
  cVector3d getPointGlobalForce(int a_index) const { return m_pointGlobalForce[static_cast<size_t>(a_index)]; }
  /// The virtual-finger joint torque (MCP, PIP) of the last computeInteractionForces() [N m].
  const uhaptics::Vec2& getFingerJointTorque() const { return m_jointTorque; }
  /// Finger joint angles (MCP, PIP) read by the last updateFromDevice() [rad].
  const uhaptics::Vec2& getFingerAngles() const { return m_fingerAngles; }
  /// Device-frame position [m] of a phalanx point at the finger angles a_x (device set).
  uhaptics::Vec3 position(const cPhalanxPoint& a_point, const uhaptics::Vec2& a_x) const;
  /// Its device-frame Jacobian d p / d x [m/rad].
  uhaptics::Mat<3, 2> jacobian(const cPhalanxPoint& a_point, const uhaptics::Vec2& a_x) const;

  /// Line colour of the drawn finger (phalanx segments).
  cColorf m_fingerColor;

 protected:
  virtual void updateToolImagePosition() {}

 private:
  cVector3d toGlobal(const uhaptics::Vec3& a_devicePoint) const;

  cExoFingerDevicePtr m_exo;
  std::vector<cPhalanxPoint> m_points;
  std::vector<cVector3d> m_pointGlobalPos;    // sized once: no allocation per frame
  std::vector<cVector3d> m_pointGlobalVel;
  std::vector<cVector3d> m_pointGlobalForce;
  uhaptics::Vec2 m_fingerAngles = uhaptics::Vec2::Zero();
  uhaptics::Vec2 m_jointTorque = uhaptics::Vec2::Zero();
  double m_proximalLength = 0.0, m_middleLength = 0.0;
};

}  // namespace chai3d
