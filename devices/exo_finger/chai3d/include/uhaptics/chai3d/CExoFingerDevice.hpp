#pragma once
// chai3d::cExoFingerDevice: one finger module of the underactuated hand exoskeleton (paper 000) as
// a CHAI3D device. One actuated joint (actuator length l_x), one sensed-only joint (rocker q_B); the
// virtual finger has two joints (MCP, PIP).
//
// CHAI3D view: the fingertip, in the finger's flexion plane mapped onto the device frame's y-z plane
// (finger pointing along +y, palm facing -z; x is never sensed nor actuated), origin at the centre
// of the fingertip's reachable region.
//
// Rendering: uhaptics::ExoFingerPolicy (exo_finger_policy.hpp: paper 000's subspace proxy, which
// reads a stock CHAI3D tool's force as the proxy spring's pull, and the figures it records in the
// session statistics, "renderer_figures" in the UHAPTICS_STATS file).
//
// Simulated backend: the finger is position-driven (paper 000's setting), following flexion-
// extension cycles whose period is the scripted hand's lap time, or, when the selection names the
// hand's waypoints (a path chosen for a scene), moving its fingertip along that path as closely as
// its joint ranges allow; the device's force loads the finger, it does not deflect it. Board backends (emulated, usb): the same renderer on the board's
// joint readings; the emulated board's finger follows paper 000's flexion-extension by itself.
#include <memory>

#include "uhaptics/backends/exo_finger_plant.hpp"
#include "uhaptics/chai3d/CUhapticsDevice.hpp"
#include "uhaptics/renderers/exo_finger_policy.hpp"

namespace chai3d {

class cExoFingerDevice;
typedef std::shared_ptr<cExoFingerDevice> cExoFingerDevicePtr;

class cExoFingerDevice : public cUhapticsDevice {
 public:
  /// Options ("options/exo/..."): coupling_stiffness Z_x [N m/rad], 0.001..100, default 1.0; force_loop_lag
  /// 1 (default) / 0: the board's force loop as a first-order lag, or ideal; method 0 (default):
  /// paper 000's nonlinear subspace proxy, 1: the standard method it improves on (S J^T F, eq. 1),
  /// for comparison. Throws uhaptics::Error when the parameter file or an option is invalid (naming
  /// it).
  cExoFingerDevice(unsigned int a_deviceNumber, const uhaptics::DeviceSelection& a_selection);
  virtual ~cExoFingerDevice();
  static cExoFingerDevicePtr create(const uhaptics::DeviceSelection& a_selection, unsigned int a_deviceNumber = 0) {
    return std::make_shared<cExoFingerDevice>(a_deviceNumber, a_selection);
  }

  /// Finger joint angles (q_MCP, q_PIP) [rad] of the latest state.
  uhaptics::Vec2 getFingerAngles();
  /// The finger's phalanx points (hand frame) of the latest state, for multi-point tools.
  uhaptics::ExoFingerPoints getFingerPoints();
  const uhaptics::ExoFingerModel& getModel() const { return m_exo->model(); }
  /// The actuator force of the latest tick [N] and the finger-joint torques the user felt [N m]
  /// (simulated backend only: a board does not sense them, zero there).
  double getActuatorForce();
  uhaptics::Vec2 getFingerTorque();
  /// Multi-point tools (cExoFingerTool): a virtual-finger joint torque (MCP, PIP) [N m] from
  /// contacts on several phalanges, added to the one read from the Cartesian force and held until
  /// replaced; rendered through the subspace proxy like that one. Non-finite input counts as zero.
  void setFingerJointTorque(const uhaptics::Vec2& a_torque);
  /// The joint torque setFingerJointTorque() holds now [N m].
  uhaptics::Vec2 getFingerJointTorque();
  /// A hand-frame point (ExoFingerPoints, model geometry) in this device's frame [m].
  uhaptics::Vec3 handToDevice(const uhaptics::Vec2& a_handPoint) const noexcept { return m_exo->handToDevice(a_handPoint); }

 protected:
  virtual std::unique_ptr<uhaptics::BoardPlant> makeSimulatedPlant();
  virtual void sessionClosed() noexcept { m_plant = nullptr; }

 private:
  using Model = uhaptics::ExoFingerModel;
  uhaptics::ExoFingerPolicy* m_exo;  // the policy (owned by cUhapticsDevice)
  const uhaptics::ExoFingerBoardPlant* m_plant = nullptr;  // sim backend: the simulated finger (getFingerTorque)
};

}  // namespace chai3d
