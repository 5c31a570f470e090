#pragma once
// Task-space Z-width: the stiffest passive wall a device renders at the tool, the quantity CHAI3D
// users set as m_maxLinearStiffness (N/m, "for a simulation running at 1 kHz"). The companion of the
// joint-space harness (zwidth.hpp), with the same classification, on the path a CHAI3D session runs:
//
//   joints (quantized to the board's resolution, rates from JointRateEstimator over the servo clock)
//   -> the device's DevicePolicy: sense() -> SensedState::position (device frame)
//   -> scene: a plane through the tool's position at the press with outward normal n,
//      F = K p n for the penetration p = (wall - position) . n > 0 (CHAI3D's spring), else 0
//   -> render(SceneInput{force = F}) -> efforts, `delay` periods late -> the plant.
//
// The plant is the device definition's make_userless_plant (TaskZWidthDevice::make_plant): no user of its own, so
// the scripted user is a force source on the tool (setUserForce, the model's task frame): a press
// along -n, a hold, a smooth release. The user's hand also damps the tool (hand_damping along every
// axis, for the whole run): a hand holding a tool is not a pure force source, and the plants' own
// damping along n is near zero (the TAU's parameter file states no joint friction), so a force-source
// user alone would leave no passive K at all. That damper belongs to the device side of the energy
// balance; the user's port is the force source, whose work is exact from the true tool point:
//
//   W_user = sum_k F_press,k . (x_k+1 - x_k),   E_generated = -W_user (readUserPoint, no sensor error)
//
// and the hand's damper brings the tool to rest after the release. Colgate and Brown's bound is then
// K < 2 b_n / T with b_n the damping the tool meets along n (the hand's plus the plant's reflected
// joint friction), identified like identifyJoint(): a sinusoidal force along n at the contact mode's
// frequency, b_n = sum F dx_n / (sum dx_n^2 / T).
//
// Renderers: a device renders the scene's force its own way (its policy); the TAU's policy picks the
// spring or the LQR wall by its contact classifier, and make_policy(renderer) forces one or the other
// ("spring", "lqr"). The LQR wall renders a plane of its own (read from the force: it holds the tool
// whatever K the scene asks), so for it the search's K is the scene's stiffness, and the stiffness it
// renders is reported: press force / penetration below the scene's plane over the end of the hold.
// A position-control wall is not a spring: it brings the tool back up to its plane from the depth the
// spring let it reach while the classifier probed, against the user's push, which the energy balance
// counts as generated. So beside the strict (passive) K_max each boundary gives k_stable, the largest
// K tried that neither bounced nor diverged (the search only brackets it: a factor up to 2).
//
// Units: m, N, N/m, N s/m, J. Not servo code: runs allocate and may throw.
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "uhaptics/backends/board_plant.hpp"
#include "uhaptics/backends/device_definition.hpp"
#include "uhaptics/experiments/reproduction.hpp"
#include "uhaptics/experiments/zwidth.hpp"
#include "uhaptics/renderers/device_policy.hpp"

namespace uhaptics::experiments {

/// A renderer's name with this suffix is that renderer under the passivity layer (PassivePolicy)...
inline constexpr const char* kPassivitySuffix = "+passivity";
/// ...and with this one under the layer observing only (the CHAI3D option passivity=2).
inline constexpr const char* kObservedPassivitySuffix = "+passivity-observe";

/// One device as the task harness drives it.
struct TaskZWidthDevice {
  std::string name;
  /// Joint and actuator counts, effort limits and per-joint sensor resolution (0: ideal).
  BoardSpec spec;
  /// A fresh plant without a user of its own (setUserForce moves it), at rest, for a servo loop of
  /// this period [s].
  std::function<std::unique_ptr<BoardPlant>(double period)> make_plant;
  /// The device's rendering policy, rendering contacts with `renderer` (one of renderers).
  std::function<std::unique_ptr<DevicePolicy>(const std::string& renderer)> make_policy;
  /// The renderers to measure; the first is the device's spring (J^T F).
  std::vector<std::string> renderers = {"spring"};
  /// Those designed for the board's servo rate only (spec.servo_rate_hz: the TAU's LQR wall and its
  /// contact classifier are built for the model's period): measured at that rate alone.
  std::vector<std::string> native_rate_renderers;
  /// The wall's outward normal, device frame (unit): the user presses along -n.
  Vec3 normal = Vec3::UnitZ();
  /// The user's hand damping on the tool [N s/m], every axis.
  double hand_damping = 0.0;
  /// Empty: measured. Otherwise why there is nothing to measure (a position-driven user).
  std::string skip_note;
  /// The plant has Coulomb friction: it dissipates in every ringing cycle and raises the boundary
  /// above the viscous bound, which then does not describe it (no bound row).
  bool coulomb_friction = false;
};

/// The press: a smooth ramp to (1 - kick_fraction) of the press force from the tool at rest on the
/// wall's plane, then a step (kick_s) to all of it, which rings the contact without lifting the tool
/// off the wall (the ring's amplitude, kick_fraction of the depth, stays below the depth). A contact
/// mode whose net damping b_n - K T / 2 is positive lets that ring decay over the hold; one whose net
/// damping is not grows it (limit cycle). A press straight from a gap would hit the wall at the speed
/// the force source gives the free tool and bounce whatever K, hiding the boundary.
struct TaskScript {
  double settle_s = 0.1;
  double press_ramp_s = 0.1;  // raised cosine: slower than the contact mode's period
  double kick_fraction = 0.2;
  double kick_s = 0.002;
  double hold_s = 0.4;
  double release_ramp_s = 0.05;
  double after_s = 0.4;
  /// At the end of the hold and of the run: where bouncing is judged; the ring's decay compares the
  /// hold's end with a window as long starting early_window_s after the kick.
  double final_window_s = 0.15;
  double early_window_s = 0.01;
  /// Penetration the press aims at [m]; the press force is K times it, at most max_press_force [N]
  /// and press_capacity_fraction of the force the device renders along n at its start
  /// (forceCapacity): a wall the actuators cannot hold lets the tool sink, which is not the Z-width.
  double press_depth = 0.003;
  double max_press_force = 8.0;
  double press_capacity_fraction = 0.5;
  double relative_tolerance = 1e-3;  // of the wall's peak stored energy
};

struct TaskWallRun {
  double stiffness = 0.0;
  WallOutcome outcome = WallOutcome::kDivergent;
  double generated_energy = 0.0;  // [J]
  double tolerance = 0.0;         // [J]
  double press_force = 0.0;       // [N]
  double max_penetration = 0.0;   // true tool point below the wall's plane [m]
  double hold_penetration = 0.0;  // mean over the last final_window_s of the hold [m]
  double hold_amplitude = 0.0;    // peak-to-peak along n there [m]
  double early_amplitude = 0.0;   // the same over the early window after the kick [m]
  int hold_entries = 0;
  double final_amplitude = 0.0;
  int final_entries = 0;
  /// press_force / hold_penetration [N/m]: the stiffness the user feels (NaN without penetration).
  double rendered_stiffness = std::numeric_limits<double>::quiet_NaN();
};

struct TaskBoundary {
  std::string renderer;
  double rate_hz = 1000.0;
  int delay = 0;
  double k_max = std::numeric_limits<double>::quiet_NaN();
  double k_fail = std::numeric_limits<double>::quiet_NaN();
  bool below_range = false;
  bool above_range = false;
  double b_n = 0.0;        // identified damping along n at this rate's contact frequency [N s/m]
  double k_colgate = 0.0;  // 2 b_n / ((1 + 2 d) T)
  /// The K_max run's rendered stiffness (the LQR wall's; the spring's is about K).
  double rendered_stiffness = std::numeric_limits<double>::quiet_NaN();
  /// The largest K run below every K that bounced or diverged (passive or active), its rendered
  /// stiffness and generated energy [J]; NaN when none.
  double k_stable = std::numeric_limits<double>::quiet_NaN();
  double rendered_stable = std::numeric_limits<double>::quiet_NaN();
  double energy_stable = std::numeric_limits<double>::quiet_NaN();
  std::vector<TaskWallRun> runs;
};

struct TaskIdentification {
  bool responds = false;
  double damping = 0.0;       // b_n [N s/m]
  double mass = 0.0;          // effective mass along n [kg] (<= 0: not mass-like)
  double frequency_hz = 0.0;
};

struct TaskZWidthOptions {
  std::vector<double> rates_hz = {500.0, 1000.0, 2000.0, 4000.0};
  std::vector<int> delays = {0};
  double relative_precision = 0.02;
  int max_bracket_steps = 6;
  TaskScript script;
  unsigned threads = 0;
};

struct DeviceTaskZWidth {
  std::string name;
  std::string note;  // why nothing was measured
  Vec3 normal = Vec3::UnitZ();
  double hand_damping = 0.0;
  double force_capacity = 0.0;  // forceCapacity() [N]
  TaskIdentification identification;  // at 20 Hz
  std::vector<TaskBoundary> boundaries;
};

/// b_n and the effective mass along n at 1 kHz, spring renderer, no scene force; frequency 0: 20 Hz
/// (the mass from the in-phase response there and at twice it).
TaskIdentification identifyTask(const TaskZWidthDevice& device, double frequency_hz = 0.0);

/// The largest force along -n the device's policy renders at its start pose before an actuator
/// reaches its effort limit [N] (from the efforts per newton of scene force; inf: none limits it).
double forceCapacity(const TaskZWidthDevice& device);

/// One press-and-release run. Throws Error for rate <= 0, delay outside 0..3 or K <= 0.
/// capacity: forceCapacity(device) (0: computed here).
TaskWallRun runTaskWall(const TaskZWidthDevice& device, const std::string& renderer, double rate_hz, int delay,
                        double stiffness, const TaskScript& script, double capacity = 0.0);

/// The search for one case: brackets from start_k by factors of 4, then bisects in log K.
TaskBoundary findTaskBoundary(const TaskZWidthDevice& device, const std::string& renderer, double rate_hz, int delay,
                              double start_k, const TaskZWidthOptions& options);

/// Every device, renderer, rate and delay, in parallel. Throws Error for invalid options.
std::vector<DeviceTaskZWidth> sweepTaskZWidth(const std::vector<TaskZWidthDevice>& devices,
                                              const TaskZWidthOptions& options,
                                              const std::function<void()>& on_boundary = {});

/// The rows the task sweep adds to the reproduction report (paper column kStabilityRows):
///  - the spring's K_max over 2 b_n / T within 10 % at 0.5 and 1 kHz and delay 0, on every device
///    whose plant the viscous bound describes (mass-like along n, b_n > 0, no Coulomb friction). At
///    2 and 4 kHz the ratio is reported, not checked: the contact mode moves into the TAU's encoder
///    quantization and above the planar arm's link modes (docs/stability.md);
///  - on every device whose specification rates its stiffness (BoardSpec::rated_stiffness, the
///    parameter file's "stability" section), the worst rated / measured K_max over the rates, per
///    delay (0 and 1), within [0.5, 1]: the rating lies inside the passive region and is derived
///    from it, not guessed far below it.
/// devices and results in the same order (sweepTaskZWidth's).
ReproductionTable taskZWidthReproduction(const std::vector<TaskZWidthDevice>& devices,
                                         const std::vector<DeviceTaskZWidth>& results);

/// The passivity layer's check at the tool: the device's spring at twice the K_max it has without
/// the layer (at that rate and delay), run with the layer on and with it observing only.
struct TaskLayerCheck {
  std::string device;
  double rate_hz = 1000.0;
  int delay = 0;
  double k_without = 0.0;  // the spring's K_max without the layer [N/m]
  double stiffness = 0.0;  // 2 k_without
  TaskWallRun layered;     // spring + kPassivitySuffix
  TaskWallRun observed;    // spring + kObservedPassivitySuffix
  /// Passive with the layer, rendering at least 0.8 of K (a layer that only scales the force down
  /// does not pass), and not passive observing only.
  bool pass() const noexcept;
};

/// For every device that renders spring + kPassivitySuffix and whose spring has a K_max at rate_hz in
/// results (the sweep's), at each delay found there: the check above.
std::vector<TaskLayerCheck> checkPassivityLayer(const std::vector<TaskZWidthDevice>& devices,
                                                const std::vector<DeviceTaskZWidth>& results, double rate_hz = 1000.0,
                                                const TaskScript& script = {});

/// The checks as reproduction rows (paper column kStabilityRows), one per device and delay: the
/// rendered stiffness over K, passing as TaskLayerCheck::pass().
ReproductionTable passivityLayerReproduction(const std::vector<TaskLayerCheck>& checks);

/// A 1-DoF point mass with viscous damping along device z (m x'' + b x' = F_user + F_actuator,
/// its "policy" J^T F = F), ideal sensor: the closed-form check, K_max = 2 b / T.
TaskZWidthDevice pointMassTaskDevice(double mass = 0.3, double damping = 3.6);

}  // namespace uhaptics::experiments
