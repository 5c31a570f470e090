#pragma once
// chai3d::cExoFingerDevice: one finger module of the underactuated hand exoskeleton (paper 000) as
// a CHAI3D device. One actuated joint (actuator length l_x), one sensed-only joint (rocker q_B); the
// virtual finger has two joints (MCP, PIP).
//
// CHAI3D view: the fingertip, in the finger's flexion plane mapped onto the device frame's y-z plane
// (finger pointing along +y, palm facing -z; x is never sensed nor actuated), origin at the centre
// of the fingertip's reachable region.
//
// Rendering (paper 000's subspace proxy): the Cartesian force F a stock CHAI3D tool sends is the
// proxy spring's pull, so it is read back as a proxy displacement through the coupling stiffness:
// finger-joint torque J_tip^T F, task proxy x_p = f(q) + Z_x^-1 J_tip^T F; the nonlinear subspace
// proxy q* = argmin |x_p - f(q*)| then gives the actuator force Z_q S (q* - q). Only what the
// actuated subspace can display is displayed, so the device stays passive (eq. 9) where projecting
// F directly (the standard method) is not.
//
// Renderer figures (session statistics, "renderer_figures" in the UHAPTICS_STATS file):
//   proxy_solves           ticks in which the subspace proxy was solved (free space skips it: the
//                          proxy is then the probe)
//   proxy_contact_ticks    of those, ticks that rendered a contact: no fault, and the application's
//                          pull (Cartesian force and multi-point joint torque, as one fingertip
//                          force) above the statistics' contact threshold, 0.05 N
//   max_proxy_distance_mm  largest fingertip distance between the probe f(q) and the proxy target
//                          the solve used, x_p [mm]
//   max_actuator_force_N   largest |actuator command| sent [N]
//   active_impedance_ticks contact ticks in which the displayed impedance d tau / d q of the method
//                          running (its theoretical form at the finger's configuration: eq. 9,
//                          -S^T Z_q S, for the subspace proxy; eq. 2, -S^T S J^T Z_x J, for the
//                          standard method) has a positive eigenvalue in its symmetric part: the
//                          device can return more energy than the proxy spring stored (paper 000,
//                          Fig. 4). Zero with the subspace proxy; the standard method couples the
//                          actuator to the sensed-only joint and goes active in parts of the range.
//
// Simulated backend: the finger is position-driven (paper 000's setting), following flexion-
// extension cycles whose period is the scripted hand's lap time, or, when the selection names the
// hand's waypoints (a path chosen for a scene), moving its fingertip along that path as closely as
// its joint ranges allow; the device's force loads the finger, it does not deflect it. Board backends (emulated, usb): the same renderer on the board's
// joint readings; the emulated board's finger follows paper 000's flexion-extension by itself.
#include <memory>

#include "uhaptics/backends/exo_finger_plant.hpp"
#include "uhaptics/chai3d/CUhapticsDevice.hpp"
#include "uhaptics/models/exo_finger_model.hpp"
#include "uhaptics/renderers/underactuated_renderers.hpp"

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

  virtual std::string getRendererName() const {
    return m_standardMethod ? uhaptics::StandardRenderer<uhaptics::ExoFingerModel>::kName
                            : uhaptics::NonlinearSubspaceRenderer<uhaptics::ExoFingerModel>::kName;
  }

  /// Finger joint angles (q_MCP, q_PIP) [rad] of the latest state.
  uhaptics::Vec2 getFingerAngles();
  /// The finger's phalanx points (hand frame) of the latest state, for multi-point tools.
  uhaptics::ExoFingerPoints getFingerPoints();
  const uhaptics::ExoFingerModel& getModel() const { return *m_model; }
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
  uhaptics::Vec3 handToDevice(const uhaptics::Vec2& a_handPoint) const noexcept;

 protected:
  virtual std::unique_ptr<uhaptics::BoardPlant> makeSimulatedPlant();
  virtual void resetRendering();
  virtual void sense(const JointReading& a_reading) noexcept;
  virtual uhaptics::Fault render(const ServoInput& a_input, double* a_efforts) noexcept;
  virtual void endSession() noexcept;

 private:
  using Model = uhaptics::ExoFingerModel;
  using Renderer = uhaptics::NonlinearSubspaceRenderer<Model>;
  uhaptics::Vec2 fingertip(const Model::TaskVector& a_x) const noexcept;
  /// d fingertip / d x (hand frame), in closed form.
  uhaptics::Mat2 fingertipJacobian(const Model::TaskVector& a_x) const noexcept;
  /// m_state from m_data (finger assembled at the latest joint reading).
  void updateState(double a_dt) noexcept;

  std::unique_ptr<const Model> m_model;  // the renderer keeps a reference to it
  const uhaptics::ExoFingerBoardPlant* m_plant = nullptr;  // sim backend: the simulated finger (getFingerTorque)
  std::unique_ptr<Renderer> m_renderer;
  std::unique_ptr<uhaptics::StandardRenderer<Model>> m_standard;
  uhaptics::ExoFingerData m_data{*m_model};
  double m_couplingStiffness;                       // Z_x (scalar), N m/rad
  const bool m_standardMethod;  // option "method" 1: paper 000's baseline instead of the subspace proxy
  uhaptics::Vec2 m_centre = uhaptics::Vec2::Zero();  // fingertip workspace centre, hand frame
  Model::ActuatorVector m_actuator = Model::ActuatorVector::Zero();
  uhaptics::Vec2 m_fingerTorqueCommand = uhaptics::Vec2::Zero();  // setFingerJointTorque()
  // Renderer figures (session statistics), see the class comment.
  int m_figureContactTicks = -1, m_figureProxyDistance = -1, m_figureActuatorForce = -1, m_figureSolves = -1,
      m_figureActiveImpedance = -1;
};

}  // namespace chai3d
