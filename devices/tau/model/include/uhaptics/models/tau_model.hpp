#pragma once
// TAU-class 6-DoF parallel haptic device (paper 001): immutable model loaded from
// devices/tau/params/tau.json + a preallocated TauData workspace made from it (Model/Data split, as in
// Pinocchio; docs/adding-a-device.md, "The model").
//
// Dynamics: a lumped-mass model in active-joint coordinates. Each actuated link is a rotor inertia
// plus a point mass on the link; each rod is split into two point masses (link tip and platform
// attachment, the usual "massless rod" lumping); platform and tool handle are point masses on the
// platform. For point masses x_k(q) the Lagrangian equations are exact:
//   M(q) qdd + c(q, qd) + g(q) = tau + J^T F_tool,
//   M = diag(I_joint) + sum_k m_k T_k^T T_k,  T_k = dx_k/dq,  c = sum_k m_k T_k^T (d^2 x_k/dt^2 at qdd = 0).
// The velocity term uses the second directional difference of x_k along qd (two warm-started forward
// kinematics solves), so no hand-derived Christoffel symbols are needed for any geometry.
#include <Eigen/LU>
#include <memory>
#include <string>
#include <vector>

#include "uhaptics/core/fault.hpp"
#include "uhaptics/core/types.hpp"
#include "uhaptics/models/tau_kinematics.hpp"

namespace uhaptics {

struct TauData;

class TauModel {
 public:
  static constexpr int kJoints = 6;
  static constexpr int kActuated = 6;
  static constexpr int kTask = 6;
  using JointVector = Vec6;
  using TaskVector = Vec6;
  using Jacobian = Mat6;
  using Selection = Mat6;
  static constexpr const char* kDeviceName = "tau";
  static constexpr int kFormatVersion = 1;

  struct PointMass {
    double mass;
    Vec3 body_point;  // platform frame
  };

  /// The mechanical stops that bound the tool's travel, as a simulation models them: one-sided
  /// spring-dampers on each position coordinate beyond +-half_side of the workspace centre and on
  /// each orientation angle beyond +-half_angle. They bound the workspace, inside the range where
  /// the mechanism assembles, so an unpowered device rests on them instead of sagging to where its
  /// kinematics have no solution.
  struct EndStops {
    double half_side = 0.025;         // m
    double half_angle = 10.0 * M_PI / 180.0;  // rad
    double stiffness = 5e4;           // N/m
    double damping = 300.0;           // N s/m
    double angular_stiffness = 30.0;  // N m/rad
    double angular_damping = 0.3;     // N m s/rad
  };

  /// Loads and validates a parameter file (devices/params/tau.json); throws uhaptics::Error naming
  /// the file and field.
  static TauModel load(const std::string& path);
  static TauModel fromParams(const ParamFile& params);
  /// Any geometry implementing TauKinematics with the given mass/limit data (for labs with real data).
  TauModel(std::shared_ptr<const TauKinematics> kinematics, const TauModel& physical_parameters);

  // --- kinematics ---------------------------------------------------------------------------
  Fault inverse(const Vec6& pose, Vec6& q) const noexcept { return kinematics_->inverse(pose, q); }
  /// Newton's method on the loop-closure equations, warm-started from data.pose. On success fills
  /// data.pose, data.J (dX/dq) and the residual/iteration count; kNotConverged at the iteration cap,
  /// kSingular when dg/dX is singular, kNonFiniteInput for NaN joints, kOutOfRange when the only
  /// solution found is another assembly mode (det(dg/dX) of another sign than at home, or the inverse
  /// does not map it back to q; e.g. after a glitched reading). data.pose is left unchanged on failure. Allocation-free.
  Fault forward(const Vec6& q, TauData& data) const noexcept;
  /// KinematicModel interface (stateless: starts from the home pose; x is NaN on failure).
  void forward(const Vec6& q, Vec6& x) const noexcept;
  void jacobian(const Vec6& q, Mat6& J) const noexcept;
  const Selection& selection() const noexcept { return selection_; }

  // --- dynamics (all need a successful forward(q, data) first) ------------------------------
  // They use its pose, J and the factorization data.lu, and leave them as they are.
  /// Mass matrix, gravity torque and (if qd != 0) velocity term into data.M, data.gravity, data.bias.
  Fault computeDynamicsTerms(const Vec6& q, const Vec6& qd, TauData& data) const noexcept;
  /// Gravity torque only (what a gravity-compensating controller needs), into data.gravity.
  void computeGravity(const Vec6& q, TauData& data) const noexcept;
  /// qdd = M^-1 (tau + J^T [f_tool; 0] - c - g). Runs forward kinematics itself.
  Fault forwardDynamics(const Vec6& q, const Vec6& qd, const Vec6& tau, const Vec3& tool_force, TauData& data,
                        Vec6& qdd) const noexcept;
  /// State derivative for x = (qd, q), u = tau: the form the LQR linearization consumes.
  Fault stateDerivative(const Vec<12>& x, const Vec6& tau, TauData& data, Vec<12>& xdot) const noexcept;

  /// Jacobian condition number with the rotational rows scaled by characteristicLength() so that
  /// metres and radians compare (m per rad of tool rotation ~ size of the handle).
  static double scaledConditionNumber(const Mat6& J, double characteristic_length);

  // --- parameters ---------------------------------------------------------------------------
  const TauKinematics& kinematics() const noexcept { return *kinematics_; }
  /// The home configuration: the platform pose and the joint angles that reach it (inverse(homePose())).
  const Vec6& homePose() const noexcept { return home_pose_; }
  const Vec6& homeJoints() const noexcept { return home_q_; }
  /// The motors' torque limits [N m].
  const Vec6& effortLimits() const noexcept { return torque_limit_; }
  int encoderCounts() const noexcept { return encoder_counts_; }
  double encoderResolution() const noexcept;  // rad per count
  double servoPeriod() const noexcept { return servo_period_; }
  int simulationSubsteps() const noexcept { return substeps_; }
  double workspaceHalfSide() const noexcept { return workspace_half_side_; }
  double workspaceHalfAngle() const noexcept { return workspace_half_angle_; }
  double characteristicLength() const noexcept { return characteristic_length_; }
  const EndStops& endStops() const noexcept { return end_stops_; }
  double fkTolerance() const noexcept { return fk_tolerance_; }
  int fkMaxIterations() const noexcept { return fk_max_iterations_; }
  const Vec3& gravityVector() const noexcept { return gravity_; }
  const std::vector<PointMass>& platformMasses() const noexcept { return platform_masses_; }
  /// Inertia about each joint axis: rotor, link, and the rod's half at the link tip (kg m^2).
  const Vec6& jointInertia() const noexcept { return joint_inertia_; }
  const Vec6& linkMass() const noexcept { return link_mass_; }
  const Vec6& linkComRadius() const noexcept { return link_com_radius_; }
  const Vec6& rodMass() const noexcept { return rod_mass_; }

 private:
  TauModel() = default;
  void finalize();
  void computeGravity(const Vec6& q, const PoseRotation& rot, TauData& data) const noexcept;

  std::shared_ptr<const TauKinematics> kinematics_;
  Selection selection_ = Selection::Identity();
  Vec6 home_pose_ = Vec6::Zero();
  Vec6 home_q_ = Vec6::Zero();
  Vec6 torque_limit_ = Vec6::Constant(2.0);
  Vec6 joint_inertia_ = Vec6::Zero();      // rotor + link about the axis (+ half rod at the tip)
  Vec6 link_mass_ = Vec6::Zero();          // link point mass (gravity)
  Vec6 link_com_radius_ = Vec6::Zero();
  Vec6 rod_mass_ = Vec6::Zero();
  Vec6 link_lever_ = Vec6::Zero();         // link mass x its radius + half rod mass x L1 (gravity)
  std::vector<PointMass> platform_masses_;  // platform, handle, rod halves
  double body_mass_ = 0.0;                   // their sum,
  Vec3 body_first_moment_ = Vec3::Zero();    // sum m c,
  Mat3 body_second_moment_ = Mat3::Zero();   // sum m c c^T (platform frame)
  Vec3 gravity_ = Vec3(0.0, 0.0, -9.81);
  int encoder_counts_ = 4096;
  double servo_period_ = 1e-3;
  int substeps_ = 10;
  double workspace_half_side_ = 0.025;
  double workspace_half_angle_ = 10.0 * M_PI / 180.0;
  double characteristic_length_ = 0.05;
  EndStops end_stops_;
  double fk_tolerance_ = 1e-12;
  int fk_max_iterations_ = 30;
  double assembly_mode_sign_ = 0.0;  // sign of det(dg/dX) at home (0: not known yet, no check)
};

/// Preallocated workspace for one device/thread.
struct TauData {
  explicit TauData(const TauModel& model) : pose(model.homePose()) {}
  Vec6 pose;                 // last forward-kinematics solution (warm start)
  Mat6 J = Mat6::Zero();     // dX/dq at pose
  Mat6 dg_dpose = Mat6::Zero();
  Mat6 dg_dq = Mat6::Zero();
  Vec6 g = Vec6::Zero();         // closure residual at pose (Newton's scratch during forward())
  Eigen::PartialPivLU<Mat6> lu;  // factorization of dg/dX at pose (likewise)
  double fk_residual = 0.0;  // max |g_i| (m) at the returned pose
  int fk_iterations = 0;
  Mat6 M = Mat6::Zero();
  Vec6 gravity = Vec6::Zero();
  Vec6 bias = Vec6::Zero();
  Vec6 scratch_pose = Vec6::Zero();
};

}  // namespace uhaptics
