#pragma once
// uhaptics::TauPolicy: how the TAU renders a scene (paper 001), on every backend and for every
// caller (device_policy.hpp).
//
// A scene sends a force, not a surface, so the surface is read from the force by the contact
// classifier (tau_contact_classifier.hpp: the engagement rule, the plane it tracks, the release
// hysteresis, the overload hand-over), fed each servo period with the scene's force and the
// position it was computed at.
//   Free space, soft objects, wall mode kSpring: the scene's own force/torque (paper 001's spring
//   baseline) is rendered, tau = J^T [F; T] + gravity compensation, scaled into the torque limits.
//   Wall mode kAuto (the default): a contact whose probed stiffness is at least stiff_threshold is
//   taken over by the LQR position-control wall; kLqr engages it after the probe whatever the
//   stiffness. While the wall holds the tool it renders the plane's normal; the scene's force across
//   the normal (a second face of a concave edge, friction, facets) is added as sent. A wall command
//   beyond a joint's torque limit is scaled down along its normal (LqrWallRenderer::Options::
//   keep_direction), so saturation never pushes the tool sideways.
//   A surface the scene knows (setContactSurface) replaces the one read from the force and is
//   rendered by the LQR wall while active, whatever the wall mode.
//
// The wall renderer runs every period: its observer must be settled when a contact begins, and in
// free space it is the gravity compensation. The LQR and its observer are designed for the command
// delay reset() is given (paper 001's board had none; the board protocol has one period), and the
// observer is told the torque that acted on the plant over the period the reading ends: the spring's
// share included, so the spring's force is not mistaken for the user's push.
//
// Figures (FigureRecorder; counts unless noted): lqr_engagements, lqr_releases, lqr_held_ticks
// (periods held by the wall), max_entry_depth_mm (maximum: how deep below the wall's plane the tool
// already was when the wall took it over, reached under the spring while the probe measured the
// stiffness), max_penetration_mm (maximum: the depth the wall let the tool sink, paper 001's < 1 mm:
// beyond the entry depth until the wall has brought the tool back within
// TauContactClassifier::kSettledDepth of its plane, then the whole depth; the plane itself is
// 0.5 N / k below the scene's surface), lqr_saturated_ticks (held periods whose wall command hit a
// torque limit), spring_contact_ticks (periods with a force of at least half contact_force rendered
// by the spring), soft_surface_contacts (contacts a probe found below stiff_threshold),
// soft_stiffness_max_N_per_m (maximum of their stiffness), lqr_overloads (contacts the wall,
// saturated for 20 ms, handed to the spring).
//
// Device frame: the model's axes (z up, gravity along -z), origin at the home pose.
#include <array>
#include <atomic>
#include <memory>

#include "uhaptics/models/tau_model.hpp"
#include "uhaptics/renderers/device_policy.hpp"
#include "uhaptics/renderers/lqr_joint_regulator.hpp"
#include "uhaptics/renderers/lqr_wall_renderer.hpp"
#include "uhaptics/renderers/tau_contact_classifier.hpp"
#include "uhaptics/renderers/tau_wall_design.hpp"

namespace uhaptics {

class TauPolicy final : public DevicePolicy {
 public:
  using WallMode = TauContactClassifier::WallMode;
  /// Paper 001's spring-wall baseline [N/m]: the stiffness a CHAI3D scene's materials are a fraction
  /// of (the device's m_maxLinearStiffness), and where the classifier places the proxy until its
  /// probe has measured the scene's.
  static constexpr double kSpringWallStiffness = 6000.0;

  struct Options {
    TauContactClassifier::Options classifier;  // servo_period is the model's; nominal_stiffness kSpringWallStiffness
    WallMode wall_mode = WallMode::kAuto;
    // N/m: the device's rated spring wall [with the command in its period, one period late]
    // (BoardSpec::rated_stiffness at the servo rate): reset() gives the classifier the one for its
    // delay as its spring_limit. NaN or <= 0: no limit.
    std::array<double, 2> rated_spring = {0.0, 0.0};
  };

  /// How the LQR wall is designed and run (designLqrWall, LqrWallRenderer::Options); the defaults
  /// are what every application gets.
  struct WallDesign {
    LqrWallWeights weights;
    bool custom_observer_noise = false;  // false: observerNoiseForDelay(the delay reset() is given)
    ObserverNoise observer_noise;
    // true: the board applies the command of d ~ U{0..D} periods ago, d drawn each period, D the
    // delay reset() is given (paper 001's CoS-D), and names it (commandApplied); designed by the
    // generalized Riccati equation with this input-rate weight [(N m)^-2].
    bool random_delay = false;
    double delay_rate_weight = 0.0;
    LqrWallRenderer::Options renderer = applicationWall();
    /// Keeps the wall's command along its normal when it saturates: a user slides the tool freely.
    static LqrWallRenderer::Options applicationWall() {
      LqrWallRenderer::Options o;
      o.keep_direction = true;
      return o;
    }
  };

  /// Throws uhaptics::Error when the LQR wall's design fails or a figure cannot be declared.
  TauPolicy(TauModel model, const Options& options, FigureRecorder& figures);

  std::string name() const override;
  void reset(int command_delay) override;
  void sense(const SensedJoints& reading, SensedState& state) noexcept override;
  /// Throws when the first reading does not assemble (forward kinematics fails).
  void checkFirstReading() const override;
  Fault render(const SceneInput& input, double* efforts) noexcept override;
  void readingLost() noexcept override;
  void endSession() noexcept override;
  /// The board's STATE names the command it applied (last_command_sequence): the wall's observer is
  /// told that command's torque for the next render() instead of the one reset()'s delay implies.
  void commandApplied(int periods_ago) noexcept override;
  /// The wall's own torque: gravity compensation, and while the LQR wall holds the tool its
  /// regulator around the plane; the rest (the spring's J^T F, the force across a held wall) is the scene's.
  void ownEfforts(double* efforts) const noexcept override;
  bool actuatedInertia(double* inertia) const override;
  Vec3 modelToDevicePoint(const Vec3& point) const noexcept override { return point - centre_; }

  const TauModel& model() const noexcept { return *model_; }
  /// The model frame's point at the device frame's origin (the home pose's position) [m].
  const Vec3& centre() const noexcept { return centre_; }
  /// Any thread.
  void setWallMode(WallMode mode) noexcept { wall_mode_ = static_cast<int>(mode); }
  WallMode wallMode() const noexcept { return static_cast<WallMode>(wall_mode_.load()); }
  /// Any thread: whether the LQR wall owns the contact (from its engagement to its release; with
  /// a known surface: while that surface holds the tool).
  bool lqrEngaged() const noexcept { return lqr_engaged_.load(); }
  /// The depth of the tool below the wall's plane [m] (0 while the wall does not hold it).
  double penetration() const noexcept { return lqr_->command().penetration; }
  /// The stiffness measured by the last contact's probe [N/m] (0 before any).
  double contactStiffness() const noexcept { return classifier_.stiffness(); }
  /// The stiffest surface an overloaded wall hands to the spring [N/m]: Options::rated_spring for
  /// the command delay reset() was given (infinity: no limit).
  double springLimit() const noexcept { return classifier_.options().spring_limit; }
  /// The wall's plane (a point on it, device frame [m], and its outward unit normal); false
  /// (outputs untouched) while there is none.
  bool contactSurface(Vec3& point, Vec3& normal) const noexcept;
  /// A surface the scene knows (device frame): while set it replaces the surface read from the
  /// force. Non-finite input: inactive. clearContactSurface() hands back to the force-read surface.
  void setContactSurface(bool active, const Vec3& point, const Vec3& normal) noexcept;
  void clearContactSurface() noexcept;
  /// Set-up: the wall's design from the next reset() on (a research protocol's; throws like reset()
  /// there).
  void setWallDesign(const WallDesign& design);

 private:
  /// The LQR wall designed at home for a command delay of delay periods (set-up: allocates, throws).
  std::unique_ptr<LqrWallRenderer> makeWall(int delay) const;
  void recordFigures(const TauContactClassifier::Events& events, const Vec3& force) noexcept;

  std::unique_ptr<const TauModel> model_;  // the renderers keep references
  FigureRecorder& figures_;
  std::unique_ptr<LqrWallRenderer> lqr_;
  std::unique_ptr<TauData> data_;  // the encoders' pose: what the wall and the scene see
  Vec3 centre_ = Vec3::Zero();
  std::atomic<int> wall_mode_;
  const std::array<double, 2> rated_spring_;  // Options::rated_spring
  std::atomic<bool> lqr_engaged_{false};
  TauContactClassifier classifier_;  // who renders the contact; the wall's plane (model frame)
  int fig_engagements_, fig_releases_, fig_held_ticks_, fig_entry_depth_, fig_max_penetration_,
      fig_saturated_ticks_, fig_spring_ticks_, fig_soft_contacts_, fig_soft_stiffness_, fig_overloads_;
  Vec6 tau_ = Vec6::Zero();
  Vec6 own_ = Vec6::Zero();  // tau_'s share that is the wall's own (ownEfforts())
  WallDesign design_;
  bool design_changed_ = false;  // setWallDesign() since lqr_ was made
  int wall_delay_ = 0;  // the command delay [periods] lqr_ is designed for
  // The torques commanded in the last periods, newest first: the wall's observer is told the one
  // acting on the plant when the reading was taken (sent_[wall_delay_], or the one the board named).
  std::array<Vec6, kMaxCommandDelay + 1> sent_;
  int applied_age_ = -1;  // commandApplied() for the next render(); -1: not reported
  Vec6 q_ = Vec6::Zero();   // the latest joint reading
  Mat3 rotation_ = Mat3::Identity();  // the handle's orientation at data_->pose
  Fault sense_fault_ = Fault::kNone;  // forward kinematics of the latest reading
  bool explicit_surface_ = false;     // setContactSurface() in force
  SurfaceContact explicit_;           // its surface, model frame
};

}  // namespace uhaptics
