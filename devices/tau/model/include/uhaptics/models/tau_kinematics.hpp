#pragma once
// Kinematics of a TAU-class 6-actuator parallel mechanism, behind an interface so that a lab with
// the real (unpublished) TAU geometry can drop in its own closed-form inverse kinematics and loop-
// closure equations; the forward kinematics (Newton), Jacobian and lumped dynamics in TauModel are
// written against this interface only.
//
// Pose convention: X = (p_x, p_y, p_z, alpha, beta, gamma) in m and rad, tool centre point (TCP) at
// the platform origin, R = Rz(gamma) Ry(beta) Rx(alpha). Each actuated joint i turns a link about a
// fixed axis at the base (motors on or near the base, as on TAU).
#include <array>
#include <memory>

#include "uhaptics/core/fault.hpp"
#include "uhaptics/core/types.hpp"

namespace uhaptics {

class ParamFile;

/// Rotation of a pose and its partial derivatives with respect to (alpha, beta, gamma).
struct PoseRotation {
  Mat3 R;
  std::array<Mat3, 3> dR;  // dR/dalpha, dR/dbeta, dR/dgamma
  explicit PoseRotation(const Vec6& pose) noexcept;
  /// R alone, for callers that need no derivatives.
  static Mat3 rotation(const Vec6& pose) noexcept;
  /// d^2R/dt^2 while the angles move at `rates` (alpha', beta', gamma') with no angular acceleration.
  Mat3 acceleration(const Vec3& rates) const noexcept;
  double cos_gamma = 1.0, sin_gamma = 0.0;  // of the pose's gamma (dR/dbeta's axis turns with it)
  /// d(p + R c)/dX for a body point c (3 x 6): [I, dR_a c, dR_b c, dR_g c].
  Mat<3, 6> pointJacobian(const Vec3& body_point) const noexcept;
};

class TauKinematics {
 public:
  virtual ~TauKinematics() = default;

  /// Closed-form inverse kinematics. Returns kOutOfRange when a chain cannot reach the pose.
  virtual Fault inverse(const Vec6& pose, Vec6& q) const noexcept = 0;

  /// Loop-closure equations g(X, q) = 0 (one per actuated chain, in metres) and their partial
  /// derivatives. The forward kinematics solves them for X by Newton's method.
  virtual void constraints(const Vec6& pose, const Vec6& q, Vec6& g, Mat6& dg_dpose, Mat6& dg_dq) const noexcept = 0;
  /// g(X, q) alone. The default evaluates constraints() and drops the derivatives.
  virtual void closure(const Vec6& pose, const Vec6& q, Vec6& g) const noexcept {
    Mat6 dg_dpose, dg_dq;
    constraints(pose, q, g, dg_dpose, dg_dq);
  }
  /// d^2/dt^2 g(X(t), q(t)) at (pose, q) moving at (pose_rate, q_rate) with X'' = 0 and q'' = 0
  /// (the closure's velocity-product term, which the dynamics' velocity term solves for). The
  /// default is a central second difference of closure() along the motion over a joint step of at
  /// most 1 mrad (truncation ~1e-6 relative).
  virtual void closureAcceleration(const Vec6& pose, const Vec6& q, const Vec6& pose_rate, const Vec6& q_rate,
                                   Vec6& g_dd) const noexcept;

  /// Whether a solution (pose, q) of the closure has every chain on the branch the mechanism is
  /// assembled in, given dg/dq there (forward() refuses the other branches). The default maps the
  /// pose back through inverse() and compares, to within `tolerance` (rad).
  virtual bool onAssembledBranches(const Vec6& pose, const Vec6& q, const Mat6& /*dg_dq*/, double tolerance) const noexcept {
    Vec6 q_back;
    return inverse(pose, q_back) == Fault::kNone && (q_back - q).cwiseAbs().maxCoeff() <= tolerance;
  }
  /// A point at `radius` along the link driven by joint i (world frame) and its derivative dq_i.
  virtual void linkPoint(int joint, double q_joint, double radius, Vec3& point, Vec3& dpoint_dq) const noexcept = 0;
  /// Length of the link driven by joint i (where the passive chain attaches).
  virtual double linkLength(int joint) const noexcept = 0;
  /// Where the passive chain of joint i attaches on the platform (platform frame).
  virtual Vec3 platformAttachment(int joint) const noexcept = 0;
};

/// Our TAU-class geometry: each actuated joint drives a link (length L1) about a fixed base axis;
/// a rod (length L2) with a universal joint at the link tip and a spherical joint on the platform
/// closes the loop (an R-U-S leg). Two legs per chain, three chains, chain 3 built differently
/// (lower, longer links, narrower platform spread). Closed-form IK per leg:
///   A cos q + B sin q = C  ->  q = atan2(B, A) + branch * acos(C / hypot(A, B)).
class RusLegKinematics final : public TauKinematics {
 public:
  struct Leg {
    Vec3 base;            // joint centre (world)
    Vec3 axis;            // unit joint axis
    Vec3 zero_direction;  // unit link direction at q = 0 (perpendicular to axis)
    Vec3 lift_direction;  // axis x zero_direction
    double link_length;   // L1
    double rod_length;    // L2
    Vec3 platform_point;  // spherical joint (platform frame)
    int branch;           // +1 or -1: which of the two IK solutions the mechanism is assembled in
  };

  explicit RusLegKinematics(const std::array<Leg, 6>& legs);
  /// Reads "legs/leg1".."legs/leg6" from a parameter file (validated; throws uhaptics::Error).
  static std::shared_ptr<const RusLegKinematics> fromParams(const ParamFile& params);

  Fault inverse(const Vec6& pose, Vec6& q) const noexcept override;
  void constraints(const Vec6& pose, const Vec6& q, Vec6& g, Mat6& dg_dpose, Mat6& dg_dq) const noexcept override;
  void closure(const Vec6& pose, const Vec6& q, Vec6& g) const noexcept override;
  /// In closed form: g_i = (|d|^2 - L2^2) / (2 L2), so g_i'' = (|d'|^2 + d . d'') / L2.
  void closureAcceleration(const Vec6& pose, const Vec6& q, const Vec6& pose_rate, const Vec6& q_rate,
                           Vec6& g_dd) const noexcept override;
  /// The branches from the signs of dg/dq alone (no inverse kinematics; see the definition).
  bool onAssembledBranches(const Vec6& pose, const Vec6& q, const Mat6& dg_dq, double tolerance) const noexcept override;
  void linkPoint(int joint, double q_joint, double radius, Vec3& point, Vec3& dpoint_dq) const noexcept override;
  double linkLength(int joint) const noexcept override { return legs_[joint].link_length; }
  Vec3 platformAttachment(int joint) const noexcept override { return legs_[joint].platform_point; }
  const Leg& leg(int i) const noexcept { return legs_[i]; }

 private:
  std::array<Leg, 6> legs_;
};

}  // namespace uhaptics
