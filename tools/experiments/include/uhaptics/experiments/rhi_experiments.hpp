#pragma once
// Paper 003's studies on the simulated 4-DoF RHI and the 3-DoF example arm, and the paper's published
// numbers with the checks against them (reproductionTable). Computation only (no files):
// uhaptics-rhi-experiments writes the CSV/PNG, tests/rhi checks the numbers.
//
// The closed-loop studies run the product: the RHI's DevicePolicy (a PlanarFmePolicy<4>) from the
// device's factory, with the paper's controller options, run by PolicyServo on what the board
// senses (its joint sensors, the shared rate estimator); the scene's wall force comes from the
// sensed end effector. The simulated device's truth feeds only the measurements (positions, the
// force sensor of the identification, joint-limit distances).
#include <array>
#include <cstddef>
#include <limits>
#include <string>
#include <vector>

#include "uhaptics/backends/simulated_planar_linkage.hpp"
#include "uhaptics/experiments/policy_servo.hpp"
#include "uhaptics/experiments/reproduction.hpp"
#include "uhaptics/models/planar_linkage_model.hpp"
#include "uhaptics/renderers/fme_null_space_controller.hpp"
#include "uhaptics/renderers/planar_fme_policy.hpp"

namespace uhaptics::rhi {

using Vec4 = Vec<4>;

using Rhi4Controller = FmeNullSpaceController<Rhi4Model>;
using Planar3Controller = FmeNullSpaceController<Planar3Model>;

Rhi4Model loadRhi4(const std::string& params_dir);
Planar3Model loadPlanar3(const std::string& params_dir);

/// The configuration whose FME matches `target` at end-effector position x: the lowest
/// nu + (k_L / beta) P over self-motion descents from 5 fixed starts and the local minima of a 10 deg
/// grid of the self-motion manifold, within the model's joint limits (the state the null-space
/// controller settles in). False when no start reaches x within limits.
bool matchedConfiguration(const Rhi4Model& model, const Vec2& x, const Mat2& target, Vec4& q);

// ---- 3-DoF example (Fig. 3-4) ------------------------------------------------------------------
struct ExampleConfiguration {
  std::string name;  // "initial", "free", "stiff"
  Vec3 q;
  Mat2 fme;          // M_hat at q
  double nu = 0.0;   // cost against the ellipsoid it was optimized for (initial: against M_free)
  double peak_force = 0.0;  // largest |alpha F_e| over the run [N]
  double min_alpha = 1.0;
};
struct ExampleSample {
  double t;
  std::array<Vec3, 3> tau;    // per configuration, after scaling
  std::array<double, 3> force_x;  // output force along x per configuration
  double demanded_x;
};
struct ExampleResult {
  double K = 0.0, zeta = 0.0;  // from q0
  Mat2 free_fme, stiff_fme;
  Vec2 x_end;  // end-effector position held fixed
  std::array<ExampleConfiguration, 3> configs;
  std::vector<ExampleSample> samples;
};
/// F_e = [3.5 sin(pi t / 2), 0] N over `duration` s at the three configurations.
ExampleResult runExample3(const Planar3Model& model, double duration = 4.0, double dt = 1e-3);

// ---- closed loop: controller + simulated RHI + virtual wall + hand --------------------------------
struct PalpationSetup {
  Vec2 x0 = Vec2(0.5, 0.1);  // start point and wall position [m]
  Vec2 u = Vec2(0.0, 1.0);   // palpation direction
  double wall_stiffness = 1000.0;  // K_e [N/m]
  double servo_dt = 1e-3;
  double substep = 1e-4;
  double hand_stiffness = 800.0;  // user's grip [N/m]
  double hand_damping = 8.0;      // [N s/m]
  double settle_time = 3.0;       // null-space reconfiguration at x0 before anything else [s]
};

struct LoopSample {
  double t;
  Vec2 x;
  Vec2 force;       // commanded (alpha F)
  double demanded;  // |F| asked by the wall
  Vec4 tau, tau_null, tau_null_command, tau_limit_command;
  double limit_distance;  // to the nearest joint limit [rad]
  double observer, omega, nu, alpha;
};

/// The RHI's policy from product (its factory makes a PlanarFmePolicy<4>) on the simulated model.
class ClosedLoop {
 public:
  /// Throws Error when product's policy is not the RHI's, or its controller refuses options.
  ClosedLoop(const Rhi4Model& model, const experiments::DeviceProduct& product, const Rhi4Controller::Options& options,
             const PalpationSetup& setup);
  /// The device at rest at q and a new session of the policy (set-up).
  void reset(const Vec4& q);
  /// Hand anchored at `anchor` (isotropic spring-damper), wall on or off, one servo period.
  void tick(const Vec2& anchor, bool wall_on);
  /// Same with an arbitrary end-effector load (identification pushes).
  void tick(const EndEffectorLoad& load, bool wall_on);
  LoopSample sample() const;
  const SimulatedPlanarLinkage<4>& device() const noexcept { return sim_; }
  Rhi4Controller& controller() noexcept { return fme_->controller(); }
  double time() const noexcept { return t_; }
  EndEffectorLoad handAt(const Vec2& anchor) const;

 private:
  PalpationSetup setup_;
  SimulatedPlanarLinkage<4> sim_;
  std::unique_ptr<DevicePolicy> policy_;
  PlanarFmePolicy<4>* fme_;
  experiments::PolicyServo servo_;
  Vec3 wall_point_, wall_normal_;  // the wall: at x0, normal -u, device frame
  double t_ = 0.0;
  Vec2 force_ = Vec2::Zero();  // the scene's, task frame
  Vec4 tau_ = Vec4::Zero();
};

// ---- Table I: palpation with the free vs the stiff ellipsoid -------------------------------------
struct IdentificationTrial {
  double push_force;  // amplitude of the multi-sine excitation along u [N]
  std::vector<std::array<double, 4>> samples;  // x_u, v_u, a_u, F_ext along u, inside the window
};
struct PalpationCase {
  std::string name;  // "free", "stiff"
  Vec4 q_settled;    // configuration after the reconfiguration at x0
  double limit_distance = 0.0;  // closest approach to a joint limit, settling and push [rad] (< 0: violated)
  double capability = 0.0;  // static maximum force along u at q_settled [N]
  double peak_force = 0.0;  // largest rendered force along u during the push [N]
  // The model's values along u (guided motion), averaged over the identification samples:
  double inertia_model = 0.0;  // u^T Lambda u [kg]
  // Joint friction reflected along u as if the joints moved as q_dot = J# v (no self-motion):
  double friction_model = 0.0; // u^T J#^T B J# u, viscous [N s/m]
  double coulomb_model = 0.0;  // sum_i c_i |(J# u)_i|, Coulomb [N]
  // The model's back-drive friction along u, (J# u)^T f(q_dot) at the samples' joint velocities
  // (self-motion included), fitted with the identifier's regressors: what the identification should
  // recover.
  double friction_reference = 0.0;  // viscous [N s/m]
  double coulomb_reference = 0.0;   // Coulomb [N]
  double inertia_identified = 0.0;  // least squares [kg]
  double friction_identified = 0.0; // viscous Phi [N s/m]
  double coulomb_identified = 0.0;  // constant (Coulomb) part of the back-drive force [N]
  double fit_rms = 0.0;             // residual of the fit [N]
  bool fit_valid = false;
  std::vector<LoopSample> push;     // the palpation run
  std::vector<IdentificationTrial> trials;
};
PalpationCase runPalpation(const Rhi4Model& model, const experiments::DeviceProduct& product, FmeEllipsoidMode mode,
                           const PalpationSetup& setup = {}, int trials = 10);

// ---- Fig. 10: workspace map of the force-capability ratio ---------------------------------------
/// Why a point's stiff/free ratio is what it is. Where the ratio comes out <= 1, a dense scan of the
/// self-motion manifold (2 deg in the first two link angles, then a descent from its best point)
/// gives the global minimum of each cost; it replaces a match that it undercuts, then the point is
/// classified.
enum class RatioKind {
  kUnreachable,          // no configuration within the joint limits reaches x
  kAbove,                // ratio > 1
  kPinnedAtSameStop,     // (b) both matches inside the limit margin of the same bound (same row, side)
  kWeakerGlobalMinimum,  // (a) the matches are the global minima and the stiff one is not stronger
  kUnexplained,          // ratio <= 1 otherwise: the dense scan found no point within the limits (c)
};
const char* toString(RatioKind kind);

struct WorkspacePoint {
  Vec2 x;
  double free_force, stiff_force, ratio;  // NaN when unreachable
  RatioKind kind = RatioKind::kUnreachable;
  // Filled where the grid-started matching gave ratio <= 1 only:
  double global_ratio;        // ratio of the global minima (the final matches)
  double free_cost_excess;    // grid-started match minus global cost (> 0: it missed the minimum)
  double stiff_cost_excess;
  double free_limit_distance, stiff_limit_distance;  // of the final matches, ratio <= 1 only [rad]
  int free_bound, stiff_bound;  // nearest bound of the matches: 2 j (lower) or 2 j + 1 (upper) of row j
  bool rematched = false;     // a match was replaced by the dense scan's lower minimum
};
/// Grid of spacing `step` over the disc of radius `max_radius` around the base; both ellipsoids are
/// matched by offline self-motion descent (matchedConfiguration; where that gives ratio <= 1 also
/// from the dense scan's minima), points with ratio <= 1 classified.
std::vector<WorkspacePoint> workspaceRatioMap(const Rhi4Model& model, double step, double max_radius,
                                              const Vec2& u = Vec2(0.0, 1.0), unsigned threads = 0);

// ---- Fig. 11: transition with and without smoothing --------------------------------------------
struct TransitionRun {
  bool smooth;
  std::vector<LoopSample> samples;
  // Largest change between consecutive ticks, |.(k) - .(k-1)|_inf [N m], and when it happened:
  double max_null_torque_jump = 0.0;  // of the FME null-space command (I - J^T J#^T)(-beta grad nu - K_d q_dot)
  double max_limit_torque_jump = 0.0;  // of the joint-limit avoidance command
  double limit_distance = 0.0;         // closest approach to a joint limit [rad]
  double jump_time = 0.0;
  double max_applied_null_jump = 0.0;  // of the applied null-space torque (after the limit scaling)
  double transition_duration = 0.0;   // rho |M_free - M_stiff|_F [s]
};
TransitionRun runTransition(const Rhi4Model& model, const experiments::DeviceProduct& product, bool smooth,
                            const PalpationSetup& setup = {});

// ---- all of paper 003's studies, their checks and summary ------------------------------------------
/// The controller's ellipsoid scales at home (mu = 5): K = mu lambda_max(M_hat_0), zeta = lambda_min / mu.
struct HomeScales {
  double K = 0.0, zeta = 0.0;
};
HomeScales homeScales(const Rhi4Model& model);

/// The workspace map in numbers: points with a finite ratio, how many lie above 1, the kinds of the
/// others, the range of the ratio.
struct WorkspaceSummary {
  std::size_t valid = 0, above = 0, pinned = 0, weaker = 0, unexplained = 0;
  std::size_t rematched = 0, lifted = 0;  // rematched from the dense scan; of them, now above 1
  double min_ratio = std::numeric_limits<double>::infinity(), max_ratio = 0.0;
};
WorkspaceSummary summarize(const std::vector<WorkspacePoint>& map);

struct StudyOptions {
  int trials = 10;            // identification pushes per ellipsoid (paper: 10)
  double map_step = 0.025;    // workspace grid spacing [m]
  unsigned threads = 0;       // for the workspace map (0: all cores)
};
struct Studies {
  HomeScales home;
  ExampleResult example;                  // 3-DoF arm, Fig. 3-4
  PalpationCase free_case, stiff_case;    // Table I
  double map_step = 0.0, map_radius = 0.0;
  std::vector<WorkspacePoint> map;        // Fig. 10
  WorkspaceSummary workspace;
  TransitionRun smooth, abrupt;           // Fig. 11
};
/// Every study at the paper's settings: the map over 0.95 of the reach.
Studies runStudies(const Rhi4Model& model, const experiments::DeviceProduct& product, const Planar3Model& arm3,
                   const StudyOptions& options = {});

/// Paper 003's published numbers next to the measured ones, with the checks that decide pass/fail.
experiments::ReproductionTable reproductionTable(const Studies& studies);
/// What the studies found, in words (summary.txt).
std::string summary(const Studies& studies);

}  // namespace uhaptics::rhi
