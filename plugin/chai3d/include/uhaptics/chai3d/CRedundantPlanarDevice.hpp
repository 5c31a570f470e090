#pragma once
// chai3d::cRedundantPlanarDevice: the 4-DoF planar redundant haptic interface (RHI) of paper 003 as
// a CHAI3D device: four actuated joints for a 2-D task, two degrees of self-motion.
//
// CHAI3D view: the device's task plane mapped onto the device frame's y-z plane (the paper's x to
// +y, its y, the palpation direction u, to -z: pressing down palpates), origin at the home
// configuration's end-effector position; x is never sensed nor actuated.
//
// Rendering: tau = J^T (alpha F) + (I - J^T J#^T) tau_S (FmeNullSpaceController): the force a stock
// CHAI3D tool sends is the primary task, rendered unchanged (scaled as a whole only when an actuator
// would saturate); the null space reshapes the force manipulability ellipsoid (light in free
// motion, strong along a stiff contact force) without changing the force at the tool.
//
// Simulated backend: SimulatedPlanarLinkage (lumped dynamics, friction, torque saturation) with the
// scripted hand's force applied at the end effector. Board backends (emulated, usb): the controller
// on the board's joint readings, joint rates from their differences over the board's sample clock.
#include <memory>

#include "uhaptics/backends/simulated_planar_linkage.hpp"
#include "uhaptics/chai3d/CUhapticsDevice.hpp"
#include "uhaptics/models/planar_linkage_model.hpp"
#include "uhaptics/renderers/fme_null_space_controller.hpp"

namespace chai3d {

class cRedundantPlanarDevice;
typedef std::shared_ptr<cRedundantPlanarDevice> cRedundantPlanarDevicePtr;

class cRedundantPlanarDevice : public cUhapticsDevice {
 public:
  using Model = uhaptics::Rhi4Model;
  using Controller = uhaptics::FmeNullSpaceController<Model>;

  /// Options ("options/rhi/<name>" in the UHAPTICS_CONFIG file, or DeviceSelection::options in
  /// code), defaults from paper 003:
  ///   mode 0     ellipsoid switching: 0 auto (saturation observer), 1 always free, 2 always stiff
  ///   mu 5       desired-ellipsoid scaling: axes mu lambda_max and lambda_min / mu of the home FME
  ///   eps1 0.7   observer level below which the stiff-contact ellipsoid is entered
  ///   eps2 0.95  observer level at which it is left (eps1 <= eps2: hysteresis)
  ///   rho 0.003  transition time per unit of ellipsoid change [s]
  ///   beta 20    null-space gradient gain;   damping 0.1   K_d [N m s/rad]
  ///   observer_shape 50   S of the saturation observer;   workspace_radius 0.1 [m]
  ///   limit_gain 0.5 [N m], limit_margin 0.25 [rad]   joint-limit barrier (0 gain: off)
  ///   limit_speed 2 [rad/s]   approach-speed cap towards the joint limits (0: off)
  /// Throws uhaptics::Error when an option is out of range (naming it) or the set is inconsistent.
  cRedundantPlanarDevice(unsigned int a_deviceNumber, const uhaptics::DeviceSelection& a_selection);
  virtual ~cRedundantPlanarDevice();
  static cRedundantPlanarDevicePtr create(const uhaptics::DeviceSelection& a_selection, unsigned int a_deviceNumber = 0) {
    return std::make_shared<cRedundantPlanarDevice>(a_deviceNumber, a_selection);
  }

  virtual std::string getRendererName() const { return "J^T F + FME null space"; }

  /// Null-space controller options from CHAI3D code (desired ellipsoid scaling mu, thresholds
  /// eps1/eps2, rho, beta, K_d = damping, fixed or automatic mode), also while the device runs;
  /// returns false and keeps the previous ones when they are invalid.
  bool setNullSpaceOptions(const Controller::Options& a_options);
  Controller::Options getNullSpaceOptions();
  /// What the controller did in the latest tick (torques, observer, ellipsoid blend, alpha).
  Controller::Status getNullSpaceStatus();
  /// Joint state of the latest tick.
  Model::JointVector getJointPositions();
  const Model& getModel() const { return *m_model; }

 protected:
  virtual void startBackend();
  virtual void stopBackend() noexcept;
  virtual uhaptics::Fault servoTick(const ServoInput& a_input, double& a_outputMagnitude) noexcept;

 private:
  void updateState() noexcept;  // m_state from the simulated device or the board's reading

  std::unique_ptr<const Model> m_model;  // the controller keeps a reference
  std::unique_ptr<uhaptics::SimulatedPlanarLinkage<4>> m_sim;
  std::unique_ptr<Controller> m_controller;
  uhaptics::Vec2 m_centre = uhaptics::Vec2::Zero();  // end effector at home, task frame
  Model::JointVector m_tau = Model::JointVector::Zero();
  Model::JointVector m_q = Model::JointVector::Zero();   // the latest joint reading
  Model::JointVector m_qd = Model::JointVector::Zero();  // its rates
  uhaptics::JointRateEstimator m_rate;                    // board backends
};

}  // namespace chai3d
