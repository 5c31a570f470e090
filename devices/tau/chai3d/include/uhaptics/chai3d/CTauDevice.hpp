#pragma once
// chai3d::cTauDevice: the TAU-class 6-DoF parallel desktop device of paper 001 (dental training) as
// a CHAI3D device: position and orientation sensed and actuated through six revolute joints.
//
// CHAI3D view: the device frame is the model's (z up, gravity along -z), origin at the workspace
// centre (home pose); rotation from the pose's three angles.
//
// Rendering: CHAI3D sends a force, not a surface, so the surface is read from the force by
// uhaptics::TauContactClassifier (tau_contact_classifier.hpp: the engagement rule, the plane it
// tracks, the release hysteresis, the overload hand-over), which this class feeds each servo tick
// with the application's force and the position it was computed at.
//   Free space, soft objects, wall option 1: the application's own force/torque (the spring
//   baseline) is rendered, tau = J^T [F; T] + gravity compensation, scaled into the torque limits.
//   Wall option 0 (the default): a contact whose stiffness, measured during a 0.2 mm probe in the
//   device frame, is at least stiff_threshold (the material's setStiffness() times the tool's
//   workspace scale factor: CHAI3D's examples set a fraction of 6000 N/m here) is taken over by the
//   LQR position-control wall; e.g. 04-shapes' spheres (0.4: 2400 N/m) and magnetic line (0.2) stay
//   with the spring, its cylinder and 23-tooth's tooth (0.8: 4800 N/m) engage the wall. Wall option
//   2 engages the wall after the probe whatever the stiffness (a soft object is then rendered rigid).
//   While the wall holds the tool it renders the plane's normal; the application's force across the
//   normal (a second face of a concave edge, friction, facets) is added as sent. The wall's command,
//   when it exceeds a joint's torque limit, is scaled down along its normal
//   (LqrWallRenderer::Options::keep_direction), so saturation never pushes the tool sideways.
//
//   Renderer figures (session statistics, counts unless noted), from the classifier's events:
//   lqr_engagements, lqr_releases, lqr_held_ticks (servo ticks held by the wall),
//   max_entry_depth_mm (maximum: how deep below the wall's plane the tool already was when the wall
//   took it over, reached under the spring while the probe measured the stiffness),
//   max_penetration_mm (maximum: the depth the wall let the tool sink, paper 001's < 1 mm: beyond
//   the entry depth until the wall has brought the tool back within
//   TauContactClassifier::kSettledDepth of its plane, then the whole depth; the plane itself is
//   0.5 N / k, 0.1 mm at 4800 N/m, below the application's surface), lqr_saturated_ticks (held
//   ticks whose wall command hit a torque limit), spring_contact_ticks (ticks with a force of at
//   least half contact_force rendered by the spring), soft_surface_contacts (contacts a probe found
//   below stiff_threshold), soft_stiffness_max_N_per_m (maximum of their stiffness), lqr_overloads
//   (contacts the wall, saturated for 20 ms, handed to the spring).
// Simulated backend: TauBoardPlant (SimulatedTau: lumped dynamics, quantized encoders, torque
// saturation) without a hand of its own: the scripted hand's force acts at the tool. On every backend
// the renderers and the scene work from the encoder readings (4096 counts per turn), velocities
// from the shared rate estimator over the device's sample clock.
#include <array>
#include <memory>

#include "uhaptics/chai3d/CUhapticsDevice.hpp"
#include "uhaptics/models/tau_model.hpp"
#include "uhaptics/renderers/lqr_wall_renderer.hpp"
#include "uhaptics/renderers/tau_contact_classifier.hpp"

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

  virtual std::string getRendererName() const;

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
  /// The wall's plane read from the force (a point on it and its outward unit normal, device frame
  /// [m]); false (outputs untouched) while there is none.
  bool getContactSurface(cVector3d& a_point, cVector3d& a_normal);
  const uhaptics::TauModel& getModel() const { return *m_model; }
  /// The surface from an application that knows its geometry (cAlgorithmLqrWall): a point on it and
  /// its outward unit normal, device frame [m]. While set it replaces the surface read from the
  /// force, and an active surface is rendered by the LQR wall whatever the wall mode;
  /// clearContactSurface() hands back to the force-read surface. Non-finite input: inactive.
  void setContactSurface(bool a_active, const cVector3d& a_point, const cVector3d& a_normal);
  void clearContactSurface();

 protected:
  virtual std::unique_ptr<uhaptics::BoardPlant> makeSimulatedPlant();
  virtual void resetRendering();
  virtual void sense(const JointReading& a_reading) noexcept;
  virtual void checkFirstReading();
  virtual uhaptics::Fault render(const ServoInput& a_input, double* a_efforts) noexcept;
  virtual void readingLost() noexcept;
  virtual void endSession() noexcept;
  virtual uhaptics::Vec3 modelToDevicePoint(const uhaptics::Vec3& a_point) const noexcept { return a_point - m_centre; }

 private:
  /// The LQR wall designed at home for a command delay of a_delay periods (set-up: allocates, throws).
  std::unique_ptr<uhaptics::LqrWallRenderer> makeWall(int a_delay) const;
  void recordFigures(const uhaptics::TauContactClassifier::Events& a_events, const uhaptics::Vec3& a_force) noexcept;
  /// m_state from an assembled pose (a_data: pose, Jacobian) at joints a_q, rates m_qd.
  void updateState(const uhaptics::TauData& a_data, const uhaptics::Vec6& a_q) noexcept;

  std::unique_ptr<const uhaptics::TauModel> m_model;  // the renderers keep references
  std::unique_ptr<uhaptics::LqrWallRenderer> m_lqr;
  std::unique_ptr<uhaptics::TauData> m_data;  // the encoders' pose: what the wall and the scene see
  uhaptics::Vec3 m_centre = uhaptics::Vec3::Zero();
  std::atomic<int> m_wallMode{C_TAU_WALL_AUTO};
  double m_toolDamping;
  std::atomic<bool> m_lqrEngaged{false};
  uhaptics::TauContactClassifier m_classifier;  // who renders the contact; the wall's plane (model frame)
  // Renderer figure ids (session statistics).
  int m_figEngagements, m_figReleases, m_figHeldTicks, m_figEntryDepth, m_figMaxPenetration, m_figSaturatedTicks,
      m_figSpringTicks, m_figSoftContacts, m_figSoftStiffness, m_figOverloads;
  uhaptics::Vec6 m_tau = uhaptics::Vec6::Zero();
  int m_wallDelay = 0;  // the command delay [periods] m_lqr is designed for
  // The torques commanded in the last periods, newest first: the wall's observer is told the one
  // acting on the plant when the reading was taken (m_sent[m_wallDelay]).
  std::array<uhaptics::Vec6, uhaptics::kMaxCommandDelay + 1> m_sent;
  uhaptics::Vec6 m_q = uhaptics::Vec6::Zero();   // the latest joint reading
  uhaptics::Vec6 m_qd = uhaptics::Vec6::Zero();  // its rates
  uhaptics::Fault m_senseFault = uhaptics::Fault::kNone;  // forward kinematics of the latest reading
  bool m_explicitSurface = false;       // setContactSurface() in force
  uhaptics::SurfaceContact m_explicit;  // its surface, model frame
};

}  // namespace chai3d
