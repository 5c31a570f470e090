#pragma once
// chai3d::cPlanarLinkageDevice<N>: a redundant planar linkage (PlanarLinkageModel<N>, N > 2) as a
// CHAI3D device, rendered with paper 003's force-manipulability null-space control: N actuated
// joints for a 2-D task, N - 2 degrees of self-motion. The devices derive from it with their model
// and title (the RHI: cRedundantPlanarDevice; paper 003's 3-DoF example arm: cPlanarArmDevice).
//
// Rendering: uhaptics::PlanarFmePolicy<N> (planar_fme_policy.hpp: the device frame, the controller,
// the figures it records in the session statistics, "renderer_figures" of the stats file), with
// this device's null-space envelope (options below).
//
// Simulated backend: PlanarLinkagePlant<N> (lumped dynamics, friction, torque saturation) with no
// grip of its own: the scripted hand's force acts at the end effector. On every backend the
// controller runs on the joint readings, rates from the shared estimator.
#include <memory>

#include "uhaptics/chai3d/CUhapticsDevice.hpp"
#include "uhaptics/renderers/planar_fme_policy.hpp"

namespace chai3d {

template <int N>
class cPlanarLinkageDevice : public cUhapticsDevice {
 public:
  using Policy = uhaptics::PlanarFmePolicy<N>;
  using Model = typename Policy::Model;
  using Controller = typename Policy::Controller;

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
  ///   null_space_tank 0 [mJ], null_space_tank_refill 0 [mW]   energy tank of the null-space
  ///                                   torque (0 capacity: none): over any T seconds the self-motion
  ///                                   control gives the arm and the hand at most tank + refill T net
  /// The three before the tank are this device's, not paper 003's. The secondary task's torque (FME gradient,
  /// damping, joint-limit barrier and brake) is scaled as a whole vector, direction kept, to a norm
  /// of at most max_null_space_torque, and after open() (or a fault that dropped it) it rises from
  /// zero as a half cosine over null_space_ramp_time: |tau_N| <= r(t) max_null_space_torque, and
  /// r grows by at most pi dt / (2 null_space_ramp_time) per tick. The primary task J^T (alpha F)
  /// keeps its full authority (the RHI's 3, 3, 1, 1 N m), so no actuator gets more than its share of J^T F
  /// plus max_null_space_torque. Why: with the paper's beta = 20 the FME gradient at the RHI's home
  /// configuration asks for more than its actuators' limits, which an empty scene would get at its
  /// first tick; the bound also caps the joint-limit terms. The axis filter keeps a CHAI3D proxy
  /// force's tick-to-tick turns, which the stiff ellipsoid's elongated axes amplify, out of the
  /// null-space torque. The tank, off unless set, bounds the energy the self-motion control gives
  /// the user (a desired ellipsoid that switches or turns sends the arm along its self-motion
  /// manifold, work only friction takes out) without damping the tool. Figures: docs/rhi.md, "In CHAI3D".
  /// Throws uhaptics::Error when an option is out of range (naming it) or the set is inconsistent.
  /// a_model: the device's model; a_title: its name in the CHAI3D specification; a_workspaceRadius:
  /// the default of the workspace_radius option [m], a disc around home well inside the reach.
  cPlanarLinkageDevice(unsigned int a_deviceNumber, const uhaptics::DeviceSelection& a_selection, Model a_model,
                       const std::string& a_title, double a_workspaceRadius);
  virtual ~cPlanarLinkageDevice();

  /// Defaults of the null-space envelope options (see above).
  static constexpr double kDefaultMaxNullSpaceTorque = Policy::kDefaultMaxNullSpaceTorque;  // [N m]
  static constexpr double kDefaultNullSpaceRampTime = Policy::kDefaultNullSpaceRampTime;    // [s]
  static constexpr double kDefaultStiffDirectionTime = Policy::kDefaultStiffDirectionTime;  // [s]

  /// Null-space controller options from CHAI3D code (desired ellipsoid scaling mu, thresholds
  /// eps1/eps2, rho, beta, K_d = damping, fixed or automatic mode, the envelope), also while the
  /// device runs; returns false and keeps the previous ones when they are invalid.
  bool setNullSpaceOptions(const typename Controller::Options& a_options);
  typename Controller::Options getNullSpaceOptions();
  /// What the controller did in the latest tick (torques, observer, ellipsoid blend, alpha).
  typename Controller::Status getNullSpaceStatus();
  /// Joint state of the latest tick.
  typename Model::JointVector getJointPositions();
  const Model& getModel() const { return m_fme->model(); }

 protected:
  virtual std::unique_ptr<uhaptics::BoardPlant> makeSimulatedPlant();

 private:
  Policy* m_fme;  // the policy (owned by cUhapticsDevice)
};

extern template class cPlanarLinkageDevice<3>;
extern template class cPlanarLinkageDevice<4>;

}  // namespace chai3d
