#pragma once
// The underactuated finger exoskeleton of paper 000: q = (l_x, q_B) -> x = (q_MCP, q_PIP).
//
// Geometry (our design; the real one is not public, devices/exo_finger/params/exo_finger.json
// documents every number). Hand frame: origin on the MCP axis, x distal, y palmar, flexion positive.
//   - The proximal exoskeleton link turns with the proximal phalanx: angle q_MCP.
//   - A rocker pivots on it at B (proximal-phalanx frame); q_B is its angle from the phalanx axis
//     (the potentiometer). A four-bar (rocker a, coupler c, output crank d on the PIP axis, fixed
//     to the middle phalanx at angle beta) gives q_PIP = psi(q_B) - beta.
//   - The actuator joins a base pivot A (hand frame) to a pin C on a rocker arm, so
//     l_x = |R(q_MCP) C(q_B) - A| couples both finger joints.
// Both closures are solved in closed form (law of cosines), which makes the map one-to-one by
// construction; the loader checks that the chosen assembly modes round-trip over the whole
// working range and that the Jacobian stays nonsingular there (tests repeat this on a dense grid).
//
// Model/Data split (docs/adding-a-device.md, "The model"): ExoFingerModel is immutable after load()
// and satisfies KinematicModel; ExoFingerData, made from the model, is a caller-owned workspace that
// forward(q, data) fills without allocating.
#include <string>

#include "uhaptics/core/joint_limits.hpp"
#include "uhaptics/core/kinematic_model.hpp"
#include "uhaptics/core/types.hpp"

namespace uhaptics {

class ParamFile;
struct ExoFingerData;

struct ExoFingerGeometry {
  double proximal_length = 0.0;  // m
  double middle_length = 0.0;    // m
  Vec2 rocker_pivot = Vec2::Zero();  // B, proximal-phalanx frame, m
  double rocker_length = 0.0;        // a
  double coupler_length = 0.0;       // c
  double output_crank_length = 0.0;  // d
  double output_crank_angle = 0.0;   // beta, rad
  double actuator_arm_length = 0.0;  // |C - B|
  double actuator_arm_angle = 0.0;   // gamma, rad, relative to the rocker
  Vec2 actuator_base = Vec2::Zero(); // A, hand frame, m
};

/// Positions (hand frame, m) of the points a CHAI3D multi-point tool follows.
struct ExoFingerPoints {
  Vec2 mcp = Vec2::Zero();
  Vec2 pip = Vec2::Zero();
  Vec2 fingertip = Vec2::Zero();          // end of the middle phalanx
  Vec2 proximal_contact = Vec2::Zero();   // mid-phalanx cuffs, where the device pushes
  Vec2 middle_contact = Vec2::Zero();
};

class ExoFingerModel {
 public:
  static constexpr int kJoints = 2;    // q = (l_x [m], q_B [rad])
  static constexpr int kActuated = 1;  // l_x
  static constexpr int kTask = 2;      // x = (q_MCP, q_PIP) [rad]
  using JointVector = Vec<kJoints>;
  using TaskVector = Vec<kTask>;
  using ActuatorVector = Vec<kActuated>;
  using Jacobian = Mat<kTask, kJoints>;
  using Selection = Mat<kActuated, kJoints>;
  static constexpr const char* kDeviceName = "exo_finger";
  static constexpr int kFormatVersion = 1;

  /// Loads and validates a parameter file (devices/params/exo_finger.json); throws uhaptics::Error
  /// naming the file and field.
  static ExoFingerModel load(const std::string& path);
  static ExoFingerModel fromParams(const ParamFile& params);

  // KinematicModel interface. Outside the assembly region the closures are continued by clamping
  // (finite, continuous); inWorkingRange() says whether q is a real configuration.
  void forward(const JointVector& q, TaskVector& x) const noexcept;
  void jacobian(const JointVector& q, Jacobian& J) const noexcept;
  /// The same Jacobian at q when x = forward(q) is already known (solvers reuse their evaluation).
  void jacobian(const JointVector& q, const TaskVector& x, Jacobian& J) const noexcept;
  const Selection& selection() const noexcept { return selection_; }
  /// Fills data for state q: forward kinematics, Jacobian, points and range flag. Allocation-free.
  void forward(const JointVector& q, ExoFingerData& data) const noexcept;

  /// Closed-form inverse q = f^-1(x). Returns false if x does not assemble (q then clamped).
  bool inverse(const TaskVector& x, JointVector& q) const noexcept;
  /// Phalanx points for finger joint angles x.
  void points(const TaskVector& x, ExoFingerPoints& p) const noexcept;

  /// Actuator inside its stroke, rocker inside its range and the finger inside its joint ranges
  /// (with tolerance tol, rad/m): q is a real configuration.
  bool inWorkingRange(const JointVector& q, double tol = 1e-9) const noexcept;
  bool taskInRange(const TaskVector& x, double tol = 1e-9) const noexcept;

  const ExoFingerGeometry& geometry() const noexcept { return geometry_; }
  const TaskVector& taskLower() const noexcept { return task_lower_; }
  const TaskVector& taskUpper() const noexcept { return task_upper_; }
  /// Per-joint stops (identity map): the actuator length range [retracted, retracted + stroke] (m)
  /// and the q_B range over the working range (rad).
  const JointLimits<kJoints>& jointLimits() const noexcept { return joint_limits_; }
  /// The actuator's force limit (N).
  const ActuatorVector& effortLimits() const noexcept { return effort_limits_; }
  double backlash() const noexcept { return backlash_; }
  double boardRateHz() const noexcept { return board_rate_hz_; }
  double hostRateHz() const noexcept { return host_rate_hz_; }
  double forceLoopTimeConstant() const noexcept { return force_loop_tau_; }
  const std::string& origin() const noexcept { return origin_; }

 private:
  ExoFingerModel() = default;
  // PIP four-bar: output angle psi for rocker angle phi (forward branch), and back (inverse branch).
  double pipFromRocker(double phi) const noexcept;
  double rockerFromPip(double pip) const noexcept;
  // MCP angle from actuator length and rocker angle, and the actuator length from both angles.
  double mcpFromActuator(double l, double phi) const noexcept;
  double actuatorLength(double mcp, double phi) const noexcept;
  Vec2 actuatorPin(double phi) const noexcept;  // C, proximal-phalanx frame
  // The joint stops of inWorkingRange() (without the finger's ranges).
  bool jointsInRange(const JointVector& q, double tol) const noexcept;

  ExoFingerGeometry geometry_;
  Selection selection_ = (Selection() << 1.0, 0.0).finished();
  TaskVector task_lower_ = TaskVector::Zero(), task_upper_ = TaskVector::Zero();
  JointLimits<kJoints> joint_limits_;
  ActuatorVector effort_limits_ = ActuatorVector::Zero();
  double backlash_ = 0.0;
  double board_rate_hz_ = 0.0, host_rate_hz_ = 0.0, force_loop_tau_ = 0.0;
  // Assembly modes (+1 / -1) of the two law-of-cosines closures, fixed at load.
  double pip_branch_ = 1.0, rocker_branch_ = 1.0, mcp_branch_ = 1.0;
  // The actuator base A's angle, norm and squared norm (hand frame), for mcpFromActuator().
  double base_angle_ = 0.0, base_norm_ = 0.0, base_squared_norm_ = 0.0;
  std::string origin_;
};

/// Workspace for one device state: everything a tick or a CHAI3D tool reads, filled in place by
/// ExoFingerModel::forward(q, data).
struct ExoFingerData {
  explicit ExoFingerData(const ExoFingerModel& /*model*/) {}
  ExoFingerModel::JointVector q = ExoFingerModel::JointVector::Zero();
  ExoFingerModel::TaskVector x = ExoFingerModel::TaskVector::Zero();
  ExoFingerModel::Jacobian J = ExoFingerModel::Jacobian::Zero();
  ExoFingerPoints points;
  bool in_range = false;
};

static_assert(kIsKinematicModel<ExoFingerModel>);

}  // namespace uhaptics
