#pragma once
// chai3d::cTauDevice: the TAU-class 6-DoF parallel desktop device of paper 001 (dental training) as
// a CHAI3D device: position and orientation sensed and actuated through six revolute joints.
//
// CHAI3D view: the device frame is the model's (z up, gravity along -z), origin at the workspace
// centre (home pose); rotation from the pose's three angles.
//
// Rendering: CHAI3D sends a force, not a surface, so the surface is read from the force.
//   - Otherwise (free space, soft objects, or wall option 1): the application's own force/torque is
//     the spring baseline, rendered as tau = J^T [F; T] + gravity compensation.
//   - When the force says a stiff surface is being pushed -- it rose faster with the tool's depth
//     since the contact began than stiff_threshold (default 3000 N/m, half the spring baseline's
//     6000 N/m that paper 001 finds the limit of stable spring walls) -- the LQR position-control
//     wall takes over: the surface is the plane through the proxy (tool + F / k) normal to F, held
//     until the tool leaves it. Wall option 2 engages the LQR wall at every contact.
// Simulated backend: SimulatedTau (lumped dynamics, quantized encoders, torque saturation) with the
// scripted hand's force applied at the tool. Board backends (emulated, usb): the same renderers on
// the board's joint readings; velocities from their differences over the board's sample clock.
#include <memory>

#include "uhaptics/backends/simulated_tau.hpp"
#include "uhaptics/chai3d/CUhapticsDevice.hpp"
#include "uhaptics/models/tau_model.hpp"
#include "uhaptics/renderers/tau_wall.hpp"

namespace chai3d {

class cTauDevice;
typedef std::shared_ptr<cTauDevice> cTauDevicePtr;

class cTauDevice : public cUhapticsDevice {
 public:
  enum cWallMode { C_TAU_WALL_AUTO = 0, C_TAU_WALL_SPRING = 1, C_TAU_WALL_LQR = 2 };

  /// Options ("options/tau/..."): wall 0 auto / 1 spring / 2 LQR; stiff_threshold [N/m], default 3000;
  /// contact_force [N] where a contact starts, default 0.3; tool_damping [N s/m], default 0;
  /// tool_rotational_damping [N m s/rad], default 0.01 (simulated handle).
  cTauDevice(unsigned int a_deviceNumber, const uhaptics::DeviceSelection& a_selection);
  virtual ~cTauDevice();
  static cTauDevicePtr create(const uhaptics::DeviceSelection& a_selection, unsigned int a_deviceNumber = 0) {
    return std::make_shared<cTauDevice>(a_deviceNumber, a_selection);
  }

  virtual std::string getRendererName() const;

  /// Switch the wall rendering at run time (e.g. from a key press).
  void setWallMode(cWallMode a_mode);
  cWallMode getWallMode();
  /// Whether the LQR wall holds the tool now, and its penetration below the surface [m].
  bool isLqrWallEngaged();
  double getLqrPenetration();
  const uhaptics::TauModel& getModel() const { return *m_model; }
  /// The surface from an application that knows its geometry (cAlgorithmLqrWall): a point on it and
  /// its outward unit normal, device frame [m]. While set it replaces the surface read from the
  /// force, and an active surface is rendered by the LQR wall whatever the wall mode;
  /// clearContactSurface() hands back to the force-read surface. Non-finite input: inactive.
  void setContactSurface(bool a_active, const cVector3d& a_point, const cVector3d& a_normal);
  void clearContactSurface();

 protected:
  virtual void startBackend();
  virtual void stopBackend() noexcept;
  virtual uhaptics::Fault servoTick(const ServoInput& a_input, double& a_outputMagnitude) noexcept;

 private:
  enum class Contact { kFree, kProbing, kLqr };
  void updateContact(const uhaptics::Vec3& a_force) noexcept;
  void updateState() noexcept;  // m_state from the simulated device or the board's reading

  std::unique_ptr<const uhaptics::TauModel> m_model;  // sim and renderers keep references
  std::unique_ptr<uhaptics::SimulatedTau> m_sim;
  std::unique_ptr<uhaptics::LqrWallRenderer> m_lqr;
  std::unique_ptr<uhaptics::TauData> m_data;
  uhaptics::Vec3 m_centre = uhaptics::Vec3::Zero();
  std::atomic<int> m_wallMode{C_TAU_WALL_AUTO};
  double m_stiffThreshold;
  double m_contactForce;
  double m_toolDamping;
  std::atomic<bool> m_lqrEngaged{false};
  // Contact read from the force: onset position, force and direction, and the latched surface.
  Contact m_contact = Contact::kFree;
  uhaptics::Vec3 m_onsetPosition = uhaptics::Vec3::Zero();
  double m_onsetForce = 0.0;
  uhaptics::SurfaceContact m_surface;
  uhaptics::Vec6 m_tau = uhaptics::Vec6::Zero();
  uhaptics::Vec6 m_q = uhaptics::Vec6::Zero();   // the latest joint reading
  uhaptics::Vec6 m_qd = uhaptics::Vec6::Zero();  // its rates (board backends)
  uhaptics::JointRateEstimator m_rate;
  bool m_explicitSurface = false;       // setContactSurface() in force
  uhaptics::SurfaceContact m_explicit;  // its surface, model frame
};

}  // namespace chai3d
