#pragma once
// Z-width harness: how stiff a virtual wall each device renders passively, at which servo rate,
// command delay and damping (Colgate and Brown, "Factors affecting the Z-width of a haptic display",
// ICRA 1994).
//
// The wall is unilateral and acts in joint space on one actuated joint j of the device's simulated
// plant, sensed as the hardware path senses it (positions quantized to the board's resolution, rates
// from JointRateEstimator, 0..3 servo periods between a reading and the period its command acts in):
//
//   p = q_j - q_wall,   u_j = min(0, -(K p + B qd_j)) while p > 0, else 0     (it pushes, never pulls)
//
// on top of the device's own free-space control (its rendering policy with no scene force: the TAU's
// gravity compensation), which belongs to the device under test. A scripted user presses joint j
// into the wall with a torque step, holds, releases along a smooth ramp and then rests on the joint
// as a light damper until the device is still. The user is a torque source on the joint, so the
// energy it receives is exact from the readings (up to their quantization):
//
//   W_user = sum_k tau_user,k (q_j,k+1 - q_j,k),     E_generated = -W_user at the end of the run,
//
// and with the device at rest at the end (the hand's damper stills it) the device and wall
// together are passive over the run exactly when E_generated <= 0. A sampled spring makes
// E_generated = (K T / 2 - b) * integral(qd_j^2) to leading order (b: the damping the joint's
// motion meets), so the boundary the classifier finds is Colgate and Brown's K = 2 b / T whatever
// the amplitude. Tolerance: a small part of the wall's peak energy plus the worst error quantized
// readings put on W_user (half a step times the total variation of the user's torque).
//
// Classification of a run (WallOutcome): divergent (non-finite or faulted plant, the joint runs away
// to 50 press depths from the wall, or oscillates wider than 10 press depths at the end of the hold
// or of the run), limit cycle (bouncing on the wall: entered it at least twice in the last
// final_window_s of the hold, while the user still pushes, or of the run), active (generated energy
// beyond the tolerance), passive.
//
// b is what the plant's joint meets: its own friction and, for plants that carry their user's grip
// (the registered TAU and planar linkages hold the end effector with a spring-damper hand), that
// grip's damping reflected to the joint. identifyJoint() measures it on the plant, without any wall,
// from the energy a sinusoidal torque on joint j puts in per cycle (W = b int qd^2 + f_c int |qd| at
// two amplitudes), at the frequency where the contact mode rings (the damping a joint of a
// multi-joint mechanism meets depends on it). The analytic bounds computed beside each boundary:
//   Colgate and Brown:   K < 2 (b - |B|) / T, and with a command delay of d periods the same
//                        energy argument with a lag of T/2 + d T: K < 2 (b - |B|) / ((1 + 2 d) T)
//                        (first order in the delay, not in the paper)
//   Abbott and Okamura:  K < 2 f_c / Delta (encoder step Delta, Coulomb friction f_c); none for an
//                        ideal sensor.
//
// Units: joint positions in rad (m for a prismatic joint), efforts in N m (N), K in N m/rad (N/m),
// B and b in N m s/rad (N s/m), energy in J. Not servo code: runs allocate and may throw.
#include <cstddef>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "uhaptics/backends/board_plant.hpp"
#include "uhaptics/backends/device_definition.hpp"
#include "uhaptics/experiments/reproduction.hpp"

namespace uhaptics::experiments {

/// The device's own control in free space, run every servo period under the wall (e.g. the TAU's
/// gravity compensation: its rendering policy with no scene force).
class FreeSpaceControl {
 public:
  virtual ~FreeSpaceControl() = default;
  /// Before a run; command_delay: periods between the reading and the period the efforts act in.
  virtual void reset(int command_delay) = 0;
  /// The actuator efforts for one period from the sensed joints and their estimated rates; first:
  /// the run's first reading. Returns false when it has no valid command (zero is then sent).
  virtual bool efforts(const double* positions, const double* rates, bool first, double period,
                       double* out) noexcept = 0;
};

/// One device as the harness drives it.
struct ZWidthDevice {
  std::string name;
  /// Joint and actuator counts, effort limits and per-joint sensor resolution (0: ideal).
  BoardSpec spec;
  /// A fresh plant at rest at its start, as the device's "sim" backend would make it, for a servo
  /// loop of this period [s] (a plant with its own fixed step may ignore it: plantResolvesPeriod).
  std::function<std::unique_ptr<BoardPlant>(double period)> make_plant;
  /// The device's free-space control; empty: none (zero efforts).
  std::function<std::unique_ptr<FreeSpaceControl>()> make_free_space;
  /// The actuated joint the wall acts on (0 .. actuators - 1).
  int joint = 0;
  /// The joint's viscous and Coulomb friction as the parameter file states them; NaN where it
  /// states none.
  double param_viscous = std::numeric_limits<double>::quiet_NaN();
  double param_coulomb = std::numeric_limits<double>::quiet_NaN();
};

/// What identifyJoint() measured of the wall joint, with no wall, on the plant as it is.
struct JointIdentification {
  /// False when the joint's motion does not depend on its effort (a position-driven user moves
  /// it, as the finger moves the exoskeleton): no Z-width to measure.
  bool responds = false;
  double damping = 0.0;       // b: viscous damping the joint's motion meets [N m s/rad] (< 0: it gains energy)
  double coulomb = 0.0;       // f_c: the velocity-independent part [N m], >= 0
  double inertia = 0.0;       // effective inertia [kg m^2] (<= 0: a stiffness dominates the response)
  double frequency_hz = 0.0;  // of the identification torque
  double amplitude = 0.0;     // of the joint's motion in the second (larger) run [rad]
};

/// One point of the sweep: servo rate, command delay, wall damping, passivity controller.
struct WallCase {
  double rate_hz = 1000.0;
  int delay = 0;             // servo periods, 0..kMaxZWidthDelay
  double damping = 0.0;      // B [N m s/rad], >= 0
  bool passivity = false;    // PassivityController on the wall joint
};
inline constexpr int kMaxZWidthDelay = 3;

enum class WallOutcome { kPassive, kActive, kLimitCycle, kDivergent };
const char* toString(WallOutcome outcome) noexcept;

/// The scripted user and the run's length.
struct WallScript {
  double settle_s = 0.1;      // device alone under its free-space control before the press
  double press_ramp_s = 0.002;  // torque step (short: it rings the contact, which shows its damping)
  double hold_s = 0.4;
  double release_ramp_s = 0.05;  // smooth (raised cosine): the joint leaves the wall slowly
  double after_s = 0.5;       // the user's hand rests on the joint as a damper
  /// That damper, per unit of the joint's identified effective inertia [1/s]: the device comes to
  /// rest within the run (the energy balance needs it at rest at the end).
  double hand_damping_per_s = 20.0;
  double final_window_s = 0.15;  // at the end of the hold and of the run: where bouncing is judged
  /// Penetration the press aims at, at least this [rad] and 20 sensor steps; the press torque is
  /// K times it, at most press_limit_fraction of the joint's effort limit.
  double press_depth = 0.01;
  double press_limit_fraction = 0.5;
  /// Energy tolerance: this fraction of the wall's peak stored energy (plus tau_press x one step).
  double relative_tolerance = 1e-3;
};

struct WallRun {
  WallCase wall;
  double stiffness = 0.0;          // K
  WallOutcome outcome = WallOutcome::kDivergent;
  double generated_energy = 0.0;   // -W_user at the end [J]
  double tolerance = 0.0;          // [J]
  double wall_energy_out = 0.0;    // the observer's E_out of the wall command as applied, sensed joints [J]
  double passivity_dissipated = 0.0;  // what the passivity controller's damping absorbed [J]
  double press_torque = 0.0;       // [N m]
  double max_penetration = 0.0;    // [rad]
  double hold_amplitude = 0.0;     // peak-to-peak of q_j over the last final_window_s of the hold [rad]
  int hold_entries = 0;            // wall entries there (the user still pushing)
  double final_amplitude = 0.0;    // peak-to-peak of q_j in the final window [rad]
  int final_entries = 0;           // wall entries in the final window
};

/// Largest passive stiffness for one case and the analytic bounds beside it.
struct Boundary {
  WallCase wall;
  /// Largest K found passive, to the search's precision; NaN when even the smallest K tried was
  /// not passive (below_range).
  double k_max = std::numeric_limits<double>::quiet_NaN();
  double k_fail = std::numeric_limits<double>::quiet_NaN();  // smallest K found not passive
  bool below_range = false;  // no passive K down to the search's floor
  bool above_range = false;  // passive up to the search's ceiling: k_max is a lower bound
  double k_colgate = 0.0;    // 2 (b - |B|) / ((1 + 2 d) T), b identified; 0 when b <= |B|
  double k_colgate_params = std::numeric_limits<double>::quiet_NaN();  // same with the file's viscous friction
  double k_quantization = std::numeric_limits<double>::infinity();     // 2 f_c / Delta (inf: ideal sensor)
  /// min(k_colgate, k_quantization) and which one it is: "Colgate-Brown" or "Abbott-Okamura".
  double k_bound = 0.0;
  std::string limiting;
  JointIdentification identification;  // what the bounds were computed from (sweepZWidth: the rate's)
  std::vector<WallRun> runs;  // every run of the search, in order
};

struct ZWidthOptions {
  std::vector<double> rates_hz = {500.0, 1000.0, 2000.0, 4000.0};
  std::vector<int> delays = {0, 1, 2, 3};
  /// Wall damping as a fraction of the identified b (each in [0, 1)), at delay 0 and without the
  /// passivity controller; 0 is always swept (every delay, with and without the controller).
  std::vector<double> damping_fractions = {0.0, 0.25, 0.5, 0.75};
  bool without_passivity = true;
  bool with_passivity = true;
  /// The search stops when the bracket [k_max, k_fail] is narrower than this ratio minus one.
  double relative_precision = 0.01;
  /// The search brackets from the bound by factors of 4, at most this many times each way.
  int max_bracket_steps = 6;
  WallScript script;
  unsigned threads = 0;  // 0: all cores
};

/// Everything the sweep found for one device.
struct DeviceZWidth {
  std::string name;
  int joint = 0;
  double resolution = 0.0;          // the joint's sensor step [rad]; 0: ideal
  JointIdentification identification;  // at the default frequency
  /// Per options.rates_hz entry: b and f_c identified at that rate's contactFrequencyHz().
  std::vector<JointIdentification> rate_identification;
  std::vector<double> skipped_rates_hz;  // faster than the plant's own integration step
  std::vector<Boundary> boundaries;
  std::string note;                 // why nothing was measured (empty: the boundaries were searched)
  /// Whether Colgate and Brown's bound describes this joint (colgateBrownApplies at 1 kHz): only
  /// there do the reproduction rows hold the measured boundary to it. bound_note: why it does not.
  bool bound_applies = false;
  std::string bound_note;
};

/// Damping cap of the passivity controller at period T and delay d: m_eff / (2 T (1 + d)), half the
/// damping that stops the joint's effective inertia in one period, divided among the periods a
/// command is late (a damper on a delayed rate that removes more than this overshoots).
double passivityMaxDamping(const JointIdentification& id, double period, int delay) noexcept;

/// Whether one call advance(period) moves the plant: false for a plant whose own integration step
/// is longer (its state only changes every few calls, so a faster servo rate is not simulated).
bool plantResolvesPeriod(const ZWidthDevice& device, double period);

/// Identifies the wall joint at 1 kHz (JointIdentification): b and f_c at frequency_hz (0: 20 Hz, or
/// lower, down to 5 Hz, until a quantized joint's motion spans 20 steps), the inertia from the
/// in-phase response there and at twice that frequency. Throws Error when the device's joint index
/// is out of range or the frequency is negative.
JointIdentification identifyJoint(const ZWidthDevice& device, double frequency_hz = 0.0);

/// Where the spring wall's contact mode rings at Colgate and Brown's bound for this rate,
/// sqrt(2 b rate / m) / (2 pi), within [5 Hz, rate / 10]; 20 Hz when b or m is not positive. The
/// damping a multi-joint plant's joint meets depends on the frequency (the other joints follow it
/// differently), so the sweep identifies b there for each rate.
double contactFrequencyHz(const JointIdentification& id, double rate_hz) noexcept;

/// One press-and-release run. free_space: the device's control (may be null), reset here.
/// Throws Error for a case out of range (rate <= 0, delay outside 0..3, B < 0, K <= 0).
WallRun runWall(const ZWidthDevice& device, const JointIdentification& id, const WallCase& wall, double stiffness,
                const WallScript& script, FreeSpaceControl* free_space);

/// The analytic bounds of a case (Boundary's k_colgate, k_colgate_params, k_quantization, k_bound,
/// limiting; nothing else is set).
Boundary analyticBounds(const ZWidthDevice& device, const JointIdentification& id, const WallCase& wall);

/// Searches K for the case: brackets from start_k by factors of 4, then bisects in log K.
Boundary findBoundary(const ZWidthDevice& device, const JointIdentification& id, const WallCase& wall,
                      double start_k, const ZWidthOptions& options, FreeSpaceControl* free_space);

/// The cases of a sweep for a joint whose identified damping is b, in the order the boundaries are
/// reported: per rate, B = 0 at every delay, then B = fraction x b at delay 0, then the passivity
/// controller at every delay (B = 0).
std::vector<WallCase> zwidthCases(const ZWidthOptions& options, double b);

/// Whether Colgate and Brown's bound K < 2 b / T describes the wall joint: it follows its effort
/// with a mass-like response (inertia > 0) and meets positive viscous damping b; Coulomb friction
/// takes under 10 % of the energy the identification dissipated (the bound leaves it out, and it
/// raises the boundary); and the device with its free-space control is passive with the wall out of
/// reach (a device whose own control delivers energy, such as a null-space controller, has no
/// passive K to bound). `id`: identified at the rate's contact frequency. False with the reason in
/// *why (when given).
bool colgateBrownApplies(const ZWidthDevice& device, const JointIdentification& id, const WallScript& script,
                         std::string* why = nullptr);

/// The whole sweep: identifies each device (the inertia on the bare plant, without its free-space
/// control, when the response with it is not mass-like), then b and f_c at each rate's contact
/// frequency, then searches every case on every device the plant resolves, in parallel
/// (options.threads). on_boundary is called after each case (any thread). Throws Error for invalid
/// options.
std::vector<DeviceZWidth> sweepZWidth(const std::vector<ZWidthDevice>& devices, const ZWidthOptions& options,
                                      const std::function<void()>& on_boundary = {});

/// The largest k_max of a device's boundaries matching (rate, delay, B = 0, passivity); NaN if none.
double boundaryStiffness(const DeviceZWidth& device, double rate_hz, int delay, bool passivity) noexcept;

/// Whether the boundary's identification resolved b: its motion at the rate's contact frequency
/// spanned at least 10 sensor steps (an ideal sensor always does). A coarse encoder at a fast rate
/// sees the contact mode move by a few counts within the effort limit; b read through them is not
/// accurate to the rows' 10 %, and the wall's boundary there is set by the quantization.
bool boundResolved(const DeviceZWidth& result, const Boundary& boundary) noexcept;

/// The rows the sweep adds to the reproduction report (paper column kStabilityRows): on every
/// device whose joint the bound describes (bound_applies), at each rate with delay 0 and B = 0 where
/// the identification resolved b (boundResolved), the measured boundary over 2 b / T within 10 %;
/// at 1 kHz the passivity controller's gain, at least 2.
ReproductionTable zwidthReproduction(const std::vector<DeviceZWidth>& results);

/// A 1-DoF mass-damper with a soft centring spring (m q'' + b q' + k q = u), integrated exactly
/// enough (RK4, steps of at most 10 us) that its passivity boundary is 2 b / T: the closed-form
/// check of the harness. Ideal sensor.
struct MassDamperParams {
  double inertia = 1e-3;      // [kg m^2]
  double damping = 0.05;      // [N m s/rad]
  double centring = 1.0;      // [N m/rad]: brings the joint back after release
  double effort_limit = 10.0;  // [N m]
};
/// Throws Error unless inertia > 0, damping >= 0, centring >= 0, effort_limit > 0 (all finite).
ZWidthDevice massDamperDevice(const MassDamperParams& params);

}  // namespace uhaptics::experiments
