#pragma once
// chai3d::cTauDevice: the TAU-class 6-DoF parallel desktop device of paper 001 (dental training) as
// a CHAI3D device: position and orientation sensed and actuated through six revolute joints.
//
// CHAI3D view: the device frame is the model's (z up, gravity along -z), origin at the workspace
// centre (home pose); rotation from the pose's three angles.
//
// Rendering: uhaptics::TauPolicy (tau_policy.hpp: paper 001's LQR wall on stiff contacts read from
// the force, the spring baseline elsewhere, and the figures it records in the session statistics).
// The options below set its classifier: stiff_threshold is the material's setStiffness() times the
// tool's workspace scale factor (CHAI3D's examples set a fraction of 6000 N/m, this device's
// m_maxLinearStiffness); e.g. 04-shapes' spheres (0.4: 2400 N/m) and magnetic line (0.2) stay with
// the spring, its cylinder and 23-tooth's tooth (0.8: 4800 N/m) engage the wall.
// Simulated backend: TauBoardPlant (SimulatedTau: lumped dynamics, quantized encoders, torque
// saturation) without a hand of its own: the scripted hand's force acts at the tool. On every backend
// the renderers and the scene work from the encoder readings (4096 counts per turn), velocities
// from the shared rate estimator over the device's sample clock.
#include <memory>

#include "uhaptics/chai3d/CUhapticsDevice.hpp"
#include "uhaptics/renderers/tau_policy.hpp"

namespace chai3d {

class cTauDevice;
typedef std::shared_ptr<cTauDevice> cTauDevicePtr;

class cTauDevice : public cUhapticsDevice {
 public:
  enum cWallMode { C_TAU_WALL_AUTO = 0, C_TAU_WALL_SPRING = 1, C_TAU_WALL_LQR = 2 };

  /// Options ("options/tau/..."): wall 0 auto / 1 spring / 2 LQR; stiff_threshold [N/m] 1..1e6, default
  /// 3000; contact_force [N] where a contact starts, 0.01..10, default 0.3; release_time [s] out of
  /// contact before the wall lets go, 0.001..1, default 0.05; tool_damping [N s/m], default 0;
  /// tool_rotational_damping [N m s/rad], default 0.01 (simulated handle).
  /// Throws uhaptics::Error when the parameter file or an option is invalid (naming it), the file's
  /// servo period is not 1 ms, or the LQR wall's design fails.
  cTauDevice(unsigned int a_deviceNumber, const uhaptics::DeviceSelection& a_selection);
  virtual ~cTauDevice();
  static cTauDevicePtr create(const uhaptics::DeviceSelection& a_selection, unsigned int a_deviceNumber = 0) {
    return std::make_shared<cTauDevice>(a_deviceNumber, a_selection);
  }

  /// Switch the wall rendering at run time (e.g. from a key press).
  void setWallMode(cWallMode a_mode);
  cWallMode getWallMode();
  /// Whether the LQR wall owns the contact now (from its engagement to its release; with
  /// setContactSurface(): while that surface holds the tool), and the depth of the tool below the
  /// wall's plane [m] (0 while the wall does not hold it).
  bool isLqrWallEngaged();
  double getLqrPenetration();
  /// The stiffness measured by the last contact's probe, device frame [N/m] (0 before any).
  double getContactStiffness();
  /// The stiffest surface the spring takes over from a saturated LQR wall, device frame [N/m]: the
  /// device's rated spring wall at its backend's command delay (set when the device opens).
  double getSpringLimit();
  /// The wall's plane read from the force (a point on it and its outward unit normal, device frame
  /// [m]); false (outputs untouched) while there is none.
  bool getContactSurface(cVector3d& a_point, cVector3d& a_normal);
  const uhaptics::TauModel& getModel() const { return m_tau->model(); }
  /// The surface from an application that knows its geometry (cAlgorithmLqrWall): a point on it and
  /// its outward unit normal, device frame [m]. While set it replaces the surface read from the
  /// force, and an active surface is rendered by the LQR wall whatever the wall mode;
  /// clearContactSurface() hands back to the force-read surface. Non-finite input: inactive.
  void setContactSurface(bool a_active, const cVector3d& a_point, const cVector3d& a_normal);
  void clearContactSurface();

 protected:
  virtual std::unique_ptr<uhaptics::BoardPlant> makeSimulatedPlant();

 private:
  uhaptics::TauPolicy* m_tau;  // the policy (owned by cUhapticsDevice)
  double m_toolDamping;
};

}  // namespace chai3d
