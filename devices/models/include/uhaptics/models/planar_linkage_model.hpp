#pragma once
// Planar N-link linkages whose links point at absolute angles that are linear in the joints:
//
//   phi_i = a_i^T q + phi0_i,   x = base + sum_i d_i e(phi_i),   e(phi) = [cos phi, sin phi]^T
//
// A serial arm with relative joint angles has a_i = [1 .. 1 0 .. 0]; the 4-DoF redundant haptic
// interface of paper 003 (a 2-DoF parallelogram robot carrying a 2-DoF PHANTOM) has
// a = [1 0 0 0; 0 1 0 0; 0 1 1 0; 0 1 0 1], phi0 = [0, -pi/2, 0, -pi/2], which reproduces the
// Jacobian of its eq. 20 exactly. Everything then follows in closed form:
//
//   J(:, j)       = sum_i d_i a_ij e'(phi_i)               e'(phi) = [-sin phi, cos phi]^T
//   dJ/dq_k(:, j) = -sum_i d_i a_ij a_ik e(phi_i)
//
// The lumped dynamics treat link i as a rigid body with its centre of mass at the middle of its
// segment (mass m_i, central inertia I_i, angular velocity a_i^T q_dot) plus a reflected rotor
// inertia per joint, moving in a horizontal plane (no gravity):
//
//   M(q) = sum_i m_i Jc_i^T Jc_i + I_i a_i a_i^T + diag(I_rotor)
//   c(q, q_dot) = sum_i m_i Jc_i^T (-sum_{l <= i} w_il e(phi_l) (a_l^T q_dot)^2)   (Coriolis/centrifugal)
//
// with Jc_i the Jacobian of centre of mass i and w_il = d_l (l < i), d_i / 2 (l = i).
// The model is immutable (loaded once from a versioned JSON file); every method is const, noexcept
// and allocation-free, so it satisfies the kinematic-model interface and the optional
// capabilities of model_capabilities.hpp (Jacobian derivative, mass matrix, joint limits). It has
// no Data workspace: forward(), jacobian() and the dynamics write into the caller's vectors
// (docs/adding-a-device.md, "The model").
#include <array>
#include <cmath>
#include <string>

#include "uhaptics/core/fault.hpp"
#include "uhaptics/core/joint_limits.hpp"
#include "uhaptics/core/types.hpp"

namespace uhaptics {

class ParamFile;

template <int N>
struct PlanarLinkageParameters {
  std::string device;          // "rhi4", "planar3"
  Vec<N> link_length;          // d_i [m]
  Mat<N, N> coupling;          // row i = a_i^T
  Vec<N> angle_offset;         // phi0_i [rad]
  Vec2 base = Vec2::Zero();    // [m]
  Vec<N> link_mass;            // [kg]
  Vec<N> link_inertia;         // about the centre of mass [kg m^2]
  Vec<N> rotor_inertia;        // reflected to the joint [kg m^2], > 0
  Vec<N> viscous_friction;     // [N m s/rad]
  Vec<N> coulomb_friction;     // [N m]
  double coulomb_velocity = 1e-3;  // smoothing of the Coulomb term, tanh(q_dot / v) [rad/s]
  Vec<N> torque_limit;         // |tau_i| <= T_i [N m]
  Vec<N> home;                 // configuration at power-on [rad]
  JointLimits<N> joint_limits; // mechanical range, lower <= C q <= upper (default: none)
};

template <int N>
class PlanarLinkageModel {
 public:
  static constexpr int kJoints = N;
  static constexpr int kActuated = N;
  static constexpr int kTask = 2;
  using JointVector = Vec<N>;
  using TaskVector = Vec2;
  using Jacobian = Mat<2, N>;
  using Selection = Mat<N, N>;
  using MassMatrix = Mat<N, N>;
  using Parameters = PlanarLinkageParameters<N>;
  static constexpr int kFormatVersion = 1;

  /// Validates p; throws uhaptics::Error naming the offending field.
  explicit PlanarLinkageModel(Parameters p);
  /// Loads and validates a parameter file (devices/<folder>/params/<device>.json, format version 1) and
  /// checks that it describes `device` with N joints; throws uhaptics::Error naming the file and
  /// field. One class serves several devices, so the device name is an argument, not a constant.
  static PlanarLinkageModel load(const std::string& path, const std::string& device);
  static PlanarLinkageModel fromParams(const ParamFile& params, const std::string& device);

  void forward(const JointVector& q, TaskVector& x) const noexcept;
  void jacobian(const JointVector& q, Jacobian& J) const noexcept;
  void jacobianDerivative(const JointVector& q, int k, Jacobian& dJ) const noexcept;
  /// forward() and jacobian() together, and every jacobianDerivative() together: the same values,
  /// the link angles' sines and cosines computed once.
  void forwardAndJacobian(const JointVector& q, TaskVector& x, Jacobian& J) const noexcept;
  void jacobianDerivatives(const JointVector& q, std::array<Jacobian, N>& dJ) const noexcept;
  void massMatrix(const JointVector& q, MassMatrix& M) const noexcept;
  /// Coriolis and centrifugal torques c(q, q_dot) (M q_ddot + c = tau).
  void velocityProductTorque(const JointVector& q, const JointVector& qd, JointVector& c) const noexcept;
  /// Joint friction torque opposing q_dot (viscous + smoothed Coulomb) and its derivative.
  void frictionTorque(const JointVector& qd, JointVector& f, JointVector* dfdqd = nullptr) const noexcept;

  // ---- inverse kinematics (set-up and analysis; allocation-free) ----
  /// Inverse kinematics from a starting guess: damped Newton steps (regularizedSolve, so a
  /// singular guess takes bounded steps) until |forward(q) - x| <= 1e-9 m. q: the guess in, the
  /// solution out. On a fault q is left as it was: kNonFiniteInput (x or q not finite), kOutOfRange
  /// (x outside the reachable disc), kNotConverged (x not reached from this guess, e.g. inside the
  /// unreachable core or at the singular rim of the workspace).
  Fault inverse(const TaskVector& x, JointVector& q) const noexcept;
  /// Closed-form inverse kinematics with the first N - 2 links at the given absolute angles
  /// (phi_0 .. phi_{N-3}, the coordinates of the self-motion manifold): the last two links close the
  /// chain as a two-link arm, elbow angle gamma = phi_{N-1} - phi_{N-2} >= 0 in q[0], <= 0 in q[1].
  /// Returns how many of q hold a solution: 0 when those two links cannot reach x (or the coupling
  /// is singular), 1 when they are stretched (gamma = 0), else 2. Joint angles are those of
  /// q = C^-1 (phi - phi0), without wrapping (nearestEquivalent wraps them).
  int closeLastTwoLinks(const TaskVector& x, const Vec<N - 2>& leading_angles,
                        std::array<JointVector, 2>& q) const noexcept;
  /// The configuration equivalent to q (whole turns added to single joints) nearest `reference`:
  /// each joint within pi of the reference's. Whole turns of one joint turn every link by whole
  /// turns when the coupling is integer, as in both devices; with a non-integer coupling q_near = q.
  void nearestEquivalent(const JointVector& q, const JointVector& reference, JointVector& q_near) const noexcept;

  const Selection& selection() const noexcept { return selection_; }
  const Parameters& parameters() const noexcept { return p_; }
  /// Configuration at power-on [rad].
  const JointVector& homeJoints() const noexcept { return p_.home; }
  /// Mechanical range, lower <= C q <= upper (no finite bound when the file gives none).
  const JointLimits<N>& jointLimits() const noexcept { return p_.joint_limits; }
  /// The actuators' torque limits, |tau_i| <= T_i [N m].
  const JointVector& effortLimits() const noexcept { return p_.torque_limit; }
  /// Sum of link lengths: the radius of the reachable disc around the base.
  double reach() const noexcept { return p_.link_length.sum(); }

 private:
  void linkAngles(const JointVector& q, JointVector& c, JointVector& s) const noexcept {
    const JointVector phi = p_.coupling * q + p_.angle_offset;
    c = phi.array().cos().matrix();
    s = phi.array().sin().matrix();
  }
  // The kinematics from the link angles' cosines c and sines s (linkAngles): the public methods
  // compute those once and share them.
  void positionAt(const JointVector& c, const JointVector& s, TaskVector& x) const noexcept;
  void jacobianAt(const JointVector& c, const JointVector& s, Jacobian& J) const noexcept;
  void jacobianDerivativeAt(const JointVector& c, const JointVector& s, int k, Jacobian& dJ) const noexcept;

  Parameters p_;
  Selection selection_ = Selection::Identity();
  Mat<N, N> coupling_inverse_ = Mat<N, N>::Zero();
  bool coupling_invertible_ = false;
  bool coupling_integer_ = false;  // whole turns of a joint leave the pose unchanged
};

using Rhi4Model = PlanarLinkageModel<4>;
using Planar3Model = PlanarLinkageModel<3>;

extern template class PlanarLinkageModel<3>;
extern template class PlanarLinkageModel<4>;

}  // namespace uhaptics
