#pragma once
// chai3d::cTauDevice: the TAU-class 6-DoF parallel desktop device of paper 001 (dental training) as
// a CHAI3D device: position and orientation sensed and actuated through six revolute joints.
//
// CHAI3D view: the device frame is the model's (z up, gravity along -z), origin at the workspace
// centre (home pose); rotation from the pose's three angles.
//
// Rendering: CHAI3D sends a force, not a surface, so the surface is read from the force.
//   Free space, soft objects, wall option 1: the application's own force/torque (the spring
//   baseline) is rendered, tau = J^T [F; T] + gravity compensation, scaled into the torque limits.
//
//   Engagement rule (wall option 0, the default). A contact starts when the application's force
//   exceeds contact_force (default 0.3 N). While the tool goes a further 0.2 mm in (the probe), the
//   device measures the scene's stiffness k = dF/dx along the contact normal in the device frame:
//   the application's spring constant after CHAI3D's workspace scaling, i.e. the material's
//   setStiffness() value times tool->getWorkspaceScaleFactor(). CHAI3D's examples set stiffness as a
//   fraction of m_maxLinearStiffness / workspaceScaleFactor, so here k = fraction x 6000 N/m.
//   k >= stiff_threshold (default 3000 N/m, half the 6000 N/m that paper 001 finds the limit of
//   stable spring walls): the LQR position-control wall takes the contact over ("lqr_engagements").
//   k below it: the spring renders the whole contact ("soft_surface_contacts", the largest such k in
//   "soft_stiffness_max_N_per_m"): a surface the spring renders stably keeps the compliance the
//   application gave it. E.g. 04-shapes' spheres (0.4: 2400 N/m) and magnetic line (0.2) stay with
//   the spring, its cylinder and 23-tooth's tooth (0.8: 4800 N/m) engage the wall. A contact too
//   light to finish the probe (its force must rise by k x 0.2 mm, ~1 N) stays with the spring and
//   counts only in "spring_contact_ticks". Wall option 2 engages the wall after the probe whatever
//   k is (a soft object is then rendered rigid).
//
//   The wall's plane follows the application's proxy. CHAI3D's proxy force is F = k (proxy - tool),
//   so the proxy is at tool + F / k, wherever the wall holds the tool. Every new force moves the
//   plane toward kHoldForce / k (0.5 N's depth) under the proxy, at most 50 mm/s along its normal;
//   so a held tool stays just inside the application's surface and its force keeps saying where
//   that surface is. The normal turns toward the application's force: along the proxy's path as
//   fast as a surface curving under a sliding proxy demands, otherwise slowly (200 ms), so that a
//   tool rocking across a concave edge does not swing the wall with it. Friction does not tilt the
//   normal: a slipping finger proxy's tangential force points against its own motion, which lies in
//   the surface, so F's component along the proxy's path is removed first. While the wall holds the
//   tool it renders the normal; the application's force across the normal (a second face of a
//   concave edge, friction, facets) is added as sent. Held with no force from the application (the
//   plane above the real surface, past the crest of a convex shape), the plane sinks at 10 mm/s.
//   The wall's command, when it exceeds a joint's torque limit, is scaled down along its normal
//   (LqrWallRenderer::Options::keep_direction), so saturation never pushes the tool sideways.
//
//   Release (hysteresis, so a contact does not flip at the tick rate): the wall stops holding as
//   soon as the tool leaves the plane (the LQR wall is unilateral); the contact ends
//   ("lqr_releases") only once the application has felt no contact for release_time (default 50 ms:
//   the tool at the plane leaves and re-enters it at the tick rate, and bounces off the wall
//   for tens of ms under a light hand) -- force below half of contact_force, or below 0.05 N while
//   the wall holds the tool (a plane above the surface). A renewed push before then is held again
//   at once, without a new probe. A wall saturated for 20 ms without a break cannot hold the
//   contact: the spring takes it over ("lqr_overloads").
//
//   Renderer figures (session statistics, counts unless noted): lqr_engagements, lqr_releases,
//   lqr_held_ticks (servo ticks held by the wall), max_entry_depth_mm (maximum: how deep below the
//   wall's plane the tool already was when the wall took it over, reached under the spring while
//   the probe measured the stiffness), max_penetration_mm (maximum: the depth the wall let the
//   tool sink, paper 001's < 1 mm: beyond the entry depth until the wall has brought the tool back
//   within kSettledDepth of its plane, then the whole depth; the plane itself is kHoldForce / k,
//   0.1 mm at 4800 N/m, below the application's surface), lqr_saturated_ticks (held ticks whose wall command hit a torque
//   limit), spring_contact_ticks (ticks with a force of at least half contact_force rendered by the
//   spring), soft_surface_contacts, soft_stiffness_max_N_per_m (maximum), lqr_overloads.
// Simulated backend: SimulatedTau (lumped dynamics, quantized encoders, torque saturation) with the
// scripted hand's force applied at the tool. Board backends (emulated, usb): the same renderers on
// the board's joint readings; velocities from their differences over the board's sample clock.
#include <array>
#include <memory>

#include "uhaptics/backends/simulated_tau.hpp"
#include "uhaptics/chai3d/CUhapticsDevice.hpp"
#include "uhaptics/models/tau_model.hpp"
#include "uhaptics/renderers/lqr_wall_renderer.hpp"

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
  virtual void startBackend();
  virtual void stopBackend() noexcept;
  virtual uhaptics::Fault servoTick(const ServoInput& a_input, double& a_outputMagnitude) noexcept;

 private:
  enum class Contact { kFree, kProbing, kSpring, kLqr };
  void startContact(const uhaptics::Vec3& a_force, int a_mode) noexcept;
  void updateContact(const uhaptics::Vec3& a_force, const uhaptics::Vec3& a_position) noexcept;
  void trackSurface(const uhaptics::Vec3& a_force, const uhaptics::Vec3& a_position, double a_stiffness,
                    double a_turnGain) noexcept;
  void release() noexcept;
  double perTick(double a_gain) const noexcept;
  void updateState() noexcept;  // m_state from the simulated device or the board's reading

  std::unique_ptr<const uhaptics::TauModel> m_model;  // sim and renderers keep references
  std::unique_ptr<uhaptics::SimulatedTau> m_sim;
  std::unique_ptr<uhaptics::LqrWallRenderer> m_lqr;
  std::unique_ptr<uhaptics::TauData> m_data;
  uhaptics::Vec3 m_centre = uhaptics::Vec3::Zero();
  std::atomic<int> m_wallMode{C_TAU_WALL_AUTO};
  double m_stiffThreshold;
  double m_contactForce;
  int m_releaseTicks;
  double m_toolDamping;
  std::atomic<bool> m_lqrEngaged{false};
  // Contact read from the force (model frame). m_held: the wall held the tool on the last tick.
  Contact m_contact = Contact::kFree;
  bool m_held = false;
  // Depth below the plane the wall inherited when it took the tool over, not charged to it as
  // penetration; zero once the tool is within kSettledDepth of the plane (a quarter of paper 001's
  // 1 mm, above the 0-0.3 mm the held tool shows with encoder noise).
  double m_entryDepth = 0.0;
  static constexpr double kSettledDepth = 0.25e-3;
  int m_quietTicks = 0;             // consecutive ticks out of contact (release hysteresis)
  uhaptics::Vec3 m_lastForce = uhaptics::Vec3::Zero();     // the application's last new force
  uhaptics::Vec3 m_lastPosition = uhaptics::Vec3::Zero();  // the position it was computed at
  int m_framesTicks = 0;            // servo ticks since the last new force
  int m_overloadTicks = 0;          // consecutive held ticks with a saturated wall command
  double m_probeForce = 0.0;        // probe: force rise and depth along the normal since the onset
  double m_probeDepth = 0.0;
  double m_stiffness = 0.0;         // measured k [N/m]
  uhaptics::Vec3 m_normal = uhaptics::Vec3::UnitZ();  // tracked surface normal
  uhaptics::Vec3 m_proxy = uhaptics::Vec3::Zero();    // the proxy at the last force that showed it
  bool m_hasProxy = false;
  static constexpr int kTrailLength = 128;
  std::array<uhaptics::Vec3, kTrailLength> m_trail;     // the proxy's last positions (ring)
  int m_trailHead = 0;
  int m_trailCount = 0;
  uhaptics::SurfaceContact m_surface;
  // Renderer figure ids (session statistics).
  int m_figEngagements, m_figReleases, m_figHeldTicks, m_figEntryDepth, m_figMaxPenetration, m_figSaturatedTicks,
      m_figSpringTicks, m_figSoftContacts, m_figSoftStiffness, m_figOverloads;
  uhaptics::Vec6 m_tau = uhaptics::Vec6::Zero();
  uhaptics::Vec6 m_q = uhaptics::Vec6::Zero();   // the latest joint reading
  uhaptics::Vec6 m_qd = uhaptics::Vec6::Zero();  // its rates (board backends)
  uhaptics::JointRateEstimator m_rate;
  bool m_explicitSurface = false;       // setContactSurface() in force
  uhaptics::SurfaceContact m_explicit;  // its surface, model frame
};

}  // namespace chai3d
