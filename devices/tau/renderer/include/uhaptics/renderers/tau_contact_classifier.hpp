#pragma once
// The TAU's contact classifier: reads the application's surface from the force it sends and decides
// who renders each contact, the application's own spring or the LQR wall (lqr_wall_renderer.hpp) on
// a plane it tracks. A haptics engine such as CHAI3D sends a force, not a surface; this class needs
// nothing of the engine (chai3d::cTauDevice feeds it each servo tick and records its events as
// session-statistics figures). Servo-rate: preallocated, every per-tick call noexcept and
// allocation-free.
//
// Engagement (wall mode kAuto). A contact starts when the application's force exceeds contact_force
// (default 0.3 N). While the tool goes a further 0.2 mm in along the onset's normal (the probe), the
// classifier measures the scene's stiffness k by a least-squares fit of the application's forces
// against the positions they were computed at, over all of the probe's new forces (the encoders'
// pose moves in steps, sideways too, and CHAI3D's proxy answers a sideways step with friction):
// the larger of the stiffest direction of the fitted stiffness matrix and the slope along the mean
// force's direction (each reads low where the other does not). k is, for CHAI3D, the material's setStiffness()
// value times tool->getWorkspaceScaleFactor(); CHAI3D's examples set stiffness as a fraction of
// m_maxLinearStiffness / workspaceScaleFactor, so k = fraction x 6000 N/m on the TAU.
// k >= stiff_threshold (default 3000 N/m, half the 6000 N/m that paper 001 finds the limit of
// stable spring walls): the LQR wall takes the contact over (Events::engaged). k below it: the
// spring renders the whole contact (Events::soft_contact): a surface the spring renders stably keeps
// the compliance the application gave it. A contact too light to finish the probe (its force must
// rise by k x 0.2 mm, ~1 N) stays with the spring. The probe measures one surface pushing the
// tool out while it goes in: a force turning against the contact's normal (the contact began on an
// effect pulling the tool in, such as CHAI3D's magnet) restarts it along the new force. Mode kLqr engages the wall after the probe
// whatever k is (a soft object is then rendered rigid); mode kSpring never engages it.
//
// The wall's plane follows the application's proxy. A proxy force is F = k (proxy - tool), so the
// proxy is at tool + F / k, wherever the wall holds the tool. Every new force moves the plane toward
// kHoldForce / k (0.5 N's depth) under the proxy, at most 50 mm/s along its normal; so a held tool
// stays just inside the application's surface and its force keeps saying where that surface is. The
// normal turns toward the application's force: along the proxy's path as fast as a surface curving
// under a sliding proxy demands, across it slowly (200 ms). A proxy that has not moved 0.5 mm (stuck
// by static friction, or in a concave edge) leaves the normal where it is: the surface under it is
// not changing, and its force's direction is only its pull on the tool, so a tool rocking across a
// concave edge or dragging a stuck proxy does not swing the wall with it. Friction does not tilt the
// normal: a slipping proxy's tangential force points against its own motion, which lies in the
// surface, so F's component along the proxy's path is removed first. Held with no force from the application (the plane above the
// real surface, past the crest of a convex shape), the plane sinks at 10 mm/s.
//
// Release (hysteresis, so a contact does not flip at the tick rate): the wall stops holding as soon
// as the tool leaves the plane (the LQR wall is unilateral); the contact ends (Events::released)
// only once the application has felt no contact for release_ticks (default 50 ms: the tool at the
// plane leaves and re-enters it at the tick rate, and bounces off the wall for tens of ms under a
// light hand) -- force below half of contact_force, or below 0.05 N while the wall holds the tool (a
// plane above the surface). A renewed push before then is held again at once, without a new probe.
// A wall saturated for 20 ms without a break cannot hold the contact: the spring takes it over
// (Events::overload, with Events::released), if the spring can render the measured surface stably
// (k within Options::spring_limit, the device's rated spring at its command delay). A stiffer surface
// stays with the wall: the spring would only bounce the tool into a growing limit cycle, which on a
// board one period late a contact that never goes quiet for release_ticks does not leave.
//
// A surface the application knows (follow()) replaces the one read from the force: while active,
// the LQR wall owns the contact whatever the wall mode.
#include <array>
#include <limits>

#include "uhaptics/core/types.hpp"
#include "uhaptics/renderers/tau_wall_front_end.hpp"

namespace uhaptics {

class TauContactClassifier {
 public:
  enum class WallMode { kAuto = 0, kSpring = 1, kLqr = 2 };
  /// kProbing: a contact the spring renders while its stiffness is measured; kSpring: one the
  /// spring renders to its end; kLqr: one the LQR wall owns (it holds the tool while at the plane).
  enum class State { kFree, kProbing, kSpring, kLqr };

  struct Options {
    double stiff_threshold = 3000.0;    // N/m: a probed stiffness from which the wall engages (kAuto)
    double contact_force = 0.3;         // N: a force above it starts a contact
    int release_ticks = 50;             // servo ticks the application feels no contact before it ends
    double nominal_stiffness = 6000.0;  // N/m: places the proxy until the probe has measured k
    double servo_period = 1e-3;         // s
    // N/m: the stiffest spring the device renders passively at its command delay (its rating); an
    // overloaded wall hands only surfaces within it to the spring. Infinite: no limit.
    double spring_limit = std::numeric_limits<double>::infinity();
  };

  /// What happened on this servo tick (update()/follow() clear it, wallTicked() completes it).
  struct Events {
    bool engaged = false;        // the LQR wall took a contact over
    bool released = false;       // a contact the LQR wall owned ended
    bool soft_contact = false;   // a probe measured a surface the spring keeps (soft_stiffness)
    double soft_stiffness = 0.0;  // N/m
    bool overload = false;       // the wall, saturated too long, handed its contact to the spring
    bool held = false;           // the wall held the tool on this tick
    bool hold_started = false;   // held, and not on the previous tick
    double entry_depth = 0.0;    // m: the depth below the plane the wall took the tool over at (hold_started)
    // m: the depth charged to the wall: beyond the entry depth until the wall has brought the tool
    // back within kSettledDepth of its plane, then the whole depth (held ticks).
    double penetration = 0.0;
    bool saturated = false;      // held, with the wall's command at a torque limit
  };

  /// Depth below the plane within which the wall counts as having settled an inherited entry depth:
  /// a quarter of paper 001's 1 mm, above the 0-0.3 mm the held tool shows with encoder noise.
  static constexpr double kSettledDepth = 0.25e-3;  // m

  /// Throws Error naming the field on a bad option (set-up code).
  explicit TauContactClassifier(const Options& options);
  /// No contact, nothing measured (the backend starts).
  void reset() noexcept;
  /// Options::spring_limit, for the command delay a session starts with (set-up code; a value
  /// that is not > 0 is no limit).
  void setSpringLimit(double limit) noexcept;

  /// Per servo tick, before the wall renderer: the application's force and the tool position it was
  /// computed at (model frame). A non-finite force or position is read as no force at the last
  /// position (it says nothing about a surface).
  void update(const Vec3& force, const Vec3& position, WallMode mode) noexcept;
  /// Per servo tick instead of update(): a surface the application gives; while it is active the LQR
  /// wall owns the contact. Engaged/released on its changes.
  void follow(const SurfaceContact& surface) noexcept;
  /// Per servo tick, after the wall renderer ticked on surface(): whether it held the tool, how
  /// deep and whether saturated.
  void wallTicked(const WallCommand& wall) noexcept;
  /// The wall's command did not reach the device (a fault): it holds nothing.
  void holdLost() noexcept;
  /// End the contact now, outside the tick (the application withdrew its surface, the backend
  /// stops). Returns true if the LQR wall owned it (a release).
  bool endContact() noexcept;

  const Events& events() const noexcept { return events_; }
  State state() const noexcept { return state_; }
  /// Whether the wall held the tool on the last tick.
  bool held() const noexcept { return held_; }
  /// The plane to hand the LQR wall (model frame): active while the wall owns the contact.
  const SurfaceContact& surface() const noexcept { return surface_; }
  /// The stiffness measured by the last contact's probe (N/m; 0 before any).
  double stiffness() const noexcept { return stiffness_; }
  const Options& options() const noexcept { return options_; }

 private:
  void startContact(const Vec3& force, WallMode mode) noexcept;
  void trackSurface(const Vec3& force, const Vec3& position, double stiffness, double turn_gain) noexcept;
  void release() noexcept;
  double perTick(double gain) const noexcept;

  Options options_;
  Events events_;
  State state_ = State::kFree;
  bool held_ = false;                  // the wall held the tool on the last tick
  double entry_depth_ = 0.0;           // inherited depth not charged as penetration (0 once settled)
  int quiet_ticks_ = 0;                // consecutive ticks out of contact (release hysteresis)
  Vec3 last_force_ = Vec3::Zero();     // the application's last new force
  Vec3 last_position_ = Vec3::Zero();  // the position it was computed at
  int frames_ticks_ = 0;               // servo ticks since the last new force
  int overload_ticks_ = 0;             // consecutive held ticks with a saturated wall command
  // The probe: a least-squares fit of force against position over its new forces (sums of the
  // samples, positions relative to the onset), and its deepest sample along the onset's normal.
  struct ProbeFit {
    int count = 0;
    Vec3 sum_x = Vec3::Zero(), sum_f = Vec3::Zero();
    Mat3 sum_xx = Mat3::Zero(), sum_xf = Mat3::Zero();
    double deepest = 0.0;  // the deepest sample below the onset, along the onset's normal [m]
    Vec3 origin = Vec3::Zero(), onset_normal = Vec3::UnitZ();
    void start(const Vec3& position, const Vec3& normal) noexcept;
    void add(const Vec3& position, const Vec3& force) noexcept;
    /// The largest eigenvalue of the symmetric part of K in F = F0 - K x, fitted over the samples.
    double stiffness() const noexcept;
  };
  ProbeFit probe_;
  double stiffness_ = 0.0;             // measured k
  Vec3 normal_ = Vec3::UnitZ();        // tracked surface normal
  Vec3 proxy_ = Vec3::Zero();          // the proxy at the last force that showed it
  bool has_proxy_ = false;
  static constexpr int kTrailLength = 128;
  std::array<Vec3, kTrailLength> trail_;  // the proxy's last positions (ring)
  int trail_head_ = 0;
  int trail_count_ = 0;
  SurfaceContact surface_;
};

}  // namespace uhaptics
