#pragma once
// chai3d::cPlanarLinkageDevice<N>: a redundant planar linkage (PlanarLinkageModel<N>, N > 2) as a
// CHAI3D device, rendered with paper 003's force-manipulability null-space control: N actuated
// joints for a 2-D task, N - 2 degrees of self-motion. The devices derive from it with their model
// and title (the RHI: cRedundantPlanarDevice; paper 003's 3-DoF example arm: cPlanarArmDevice).
//
// CHAI3D view: the device's task plane mapped onto the device frame's y-z plane (the paper's x to
// +y, its y, the palpation direction u, to -z: pressing down palpates), origin at the home
// configuration's end-effector position; x is never sensed nor actuated.
//
// Rendering: tau = J^T (alpha F) + (I - J^T J#^T) tau_S (FmeNullSpaceController): the force a stock
// CHAI3D tool sends is the primary task, rendered unchanged (scaled as a whole only when an actuator
// would saturate); the null space reshapes the force manipulability ellipsoid (light in free
// motion, strong along a stiff contact force) without changing the force at the tool, within a
// bounded, ramped envelope (options below).
//
// Renderer figures (session statistics, "renderer_figures" of the stats file):
//   free_to_stiff              count: switches of the desired ellipsoid towards the stiff-contact one
//                              (the observer fell below eps1, or mode changed to 2)
//   stiff_to_free              count: switches back towards the free-motion one (a reversal during a
//                              blend counts as a switch)
//   stiff_ticks                count: ticks with any share of the stiff-contact ellipsoid in the
//                              desired one (omega < 1), both blends included
//   max_force_scale_reduction  maximum of 1 - alpha, the uniform force scaling before an actuator
//                              saturates (0: the force was never scaled)
//   max_null_space_torque_Nm   maximum Euclidean norm of the applied null-space torque [N m]
//
// Simulated backend: PlanarLinkagePlant<N> (lumped dynamics, friction, torque saturation) with no
// grip of its own: the scripted hand's force acts at the end effector. On every backend the
// controller runs on the joint readings (rates exact from the simulation, else their differences
// over the board's sample clock).
#include <memory>

#include "uhaptics/chai3d/CUhapticsDevice.hpp"
#include "uhaptics/models/planar_linkage_model.hpp"
#include "uhaptics/renderers/fme_null_space_controller.hpp"

namespace chai3d {

template <int N>
class cPlanarLinkageDevice : public cUhapticsDevice {
 public:
  using Model = uhaptics::PlanarLinkageModel<N>;
  using Controller = uhaptics::FmeNullSpaceController<Model>;

  /// Options ("options/<device>/<name>" in the UHAPTICS_CONFIG file, or DeviceSelection::options in
  /// code), defaults from paper 003:
  ///   mode 0     ellipsoid switching: 0 auto (saturation observer), 1 always free, 2 always stiff
  ///   mu 5       desired-ellipsoid scaling: axes mu lambda_max and lambda_min / mu of the home FME
  ///   eps1 0.7   observer level below which the stiff-contact ellipsoid is entered
  ///   eps2 0.95  observer level at which it is left (eps1 <= eps2: hysteresis)
  ///   rho 0.003  transition time per unit of ellipsoid change [s]
  ///   beta 20    null-space gradient gain;   damping 0.1   K_d [N m s/rad]
  ///   observer_shape 50   S of the saturation observer;   workspace_radius [m] (the device's default)
  ///   limit_gain 0.5 [N m], limit_margin 0.25 [rad]   joint-limit barrier (0 gain: off)
  ///   limit_speed 2 [rad/s]   approach-speed cap towards the joint limits (0: off)
  ///   max_null_space_torque 0.5 [N m]   bound on the norm of the null-space torque, in [0.01, 10]
  ///   null_space_ramp_time 0.25 [s]   rise time of the null-space torque after open(), in [0, 10]
  ///   stiff_direction_time 0.02 [s]   time constant of the stiff ellipsoid's axis following the
  ///                                   contact force's direction, in [0, 1] (0: each tick's force)
  /// The last three are this device's, not paper 003's. The secondary task's torque (FME gradient,
  /// damping, joint-limit barrier and brake) is scaled as a whole vector, direction kept, to a norm
  /// of at most max_null_space_torque, and after open() (or a fault that dropped it) it rises from
  /// zero as a half cosine over null_space_ramp_time: |tau_N| <= r(t) max_null_space_torque, and
  /// r grows by at most pi dt / (2 null_space_ramp_time) per tick. The primary task J^T (alpha F)
  /// keeps its full authority (the RHI's 3, 3, 1, 1 N m), so no actuator gets more than its share of J^T F
  /// plus max_null_space_torque. Why: with the paper's beta = 20 the FME gradient at the RHI's home
  /// configuration asks for more than its actuators' limits, which an empty scene would get at its
  /// first tick; the bound also caps the joint-limit terms. The axis filter keeps a CHAI3D proxy
  /// force's tick-to-tick turns, which the stiff ellipsoid's elongated axes amplify, out of the
  /// null-space torque. Figures: docs/rhi.md, "In CHAI3D".
  /// Throws uhaptics::Error when an option is out of range (naming it) or the set is inconsistent.
  /// a_model: the device's model; a_title: its name in the CHAI3D specification; a_workspaceRadius:
  /// the default of the workspace_radius option [m], a disc around home well inside the reach.
  cPlanarLinkageDevice(unsigned int a_deviceNumber, const uhaptics::DeviceSelection& a_selection, Model a_model,
                       const std::string& a_title, double a_workspaceRadius);
  virtual ~cPlanarLinkageDevice();

  virtual std::string getRendererName() const { return "J^T F + FME null space"; }

  /// Defaults of the null-space envelope options (see above).
  static constexpr double kDefaultMaxNullSpaceTorque = 0.5;  // [N m]
  static constexpr double kDefaultNullSpaceRampTime = 0.25;  // [s]
  static constexpr double kDefaultStiffDirectionTime = 0.02;  // [s]

  /// Null-space controller options from CHAI3D code (desired ellipsoid scaling mu, thresholds
  /// eps1/eps2, rho, beta, K_d = damping, fixed or automatic mode, the envelope), also while the
  /// device runs; returns false and keeps the previous ones when they are invalid.
  bool setNullSpaceOptions(const typename Controller::Options& a_options);
  typename Controller::Options getNullSpaceOptions();
  /// What the controller did in the latest tick (torques, observer, ellipsoid blend, alpha).
  typename Controller::Status getNullSpaceStatus();
  /// Joint state of the latest tick.
  typename Model::JointVector getJointPositions();
  const Model& getModel() const { return *m_model; }

 protected:
  virtual std::unique_ptr<uhaptics::BoardPlant> makeSimulatedPlant();
  virtual void resetRendering();
  virtual void sense(const JointReading& a_reading) noexcept;
  virtual uhaptics::Fault render(const ServoInput& a_input, double* a_efforts) noexcept;
  virtual uhaptics::Vec3 deviceToModelForce(const uhaptics::Vec3& a_force) const noexcept { return this->planarForce(a_force); }
  virtual uhaptics::Vec3 modelToDevicePoint(const uhaptics::Vec3& a_point) const noexcept {
    return this->planarToDevice(a_point.template head<2>() - m_centre);
  }
  virtual uhaptics::Vec3 modelToDeviceVector(const uhaptics::Vec3& a_vector) const noexcept {
    return this->planarToDevice(a_vector.template head<2>());
  }

 private:
  void updateState() noexcept;  // m_state from m_q, m_qd
  void recordFigures(const typename Controller::Status& a_status) noexcept;  // the renderer figures of one tick

  std::unique_ptr<const Model> m_model;  // the controller keeps a reference
  std::unique_ptr<Controller> m_controller;
  uhaptics::Vec2 m_centre = uhaptics::Vec2::Zero();  // end effector at home, task frame
  typename Model::JointVector m_tau = Model::JointVector::Zero();
  typename Model::JointVector m_q = Model::JointVector::Zero();   // the latest joint reading
  typename Model::JointVector m_qd = Model::JointVector::Zero();  // its rates
  // Renderer figures (session statistics): ids, and whether the last tick headed for the stiff ellipsoid.
  int m_figureFreeToStiff = -1, m_figureStiffToFree = -1, m_figureStiffTicks = -1;
  int m_figureForceScaleReduction = -1, m_figureNullSpaceTorque = -1;
  bool m_stiffTarget = false;
};

extern template class cPlanarLinkageDevice<3>;
extern template class cPlanarLinkageDevice<4>;

}  // namespace chai3d
