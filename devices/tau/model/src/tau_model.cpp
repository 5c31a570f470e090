#include "uhaptics/models/tau_model.hpp"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <sstream>

#include "uhaptics/core/lu_condition.hpp"
#include "uhaptics/models/param_file.hpp"

namespace uhaptics {
namespace {

// Newton's method on g(X, q) = 0 for X. Uses data.g/dg_*/lu as scratch. Returns kNone with the
// factorization of dg/dX at the solution left in data.lu.
Fault solvePose(const TauKinematics& kin, const Vec6& q, double tol, int max_iterations, Vec6& X, TauData& data,
                double& residual, int& iterations) noexcept {
  iterations = 0;
  residual = std::numeric_limits<double>::infinity();
  for (int it = 0; it <= max_iterations; ++it) {
    kin.constraints(X, q, data.g, data.dg_dpose, data.dg_dq);
    residual = data.g.cwiseAbs().maxCoeff();
    if (!std::isfinite(residual)) return Fault::kNonFiniteResult;
    data.lu.compute(data.dg_dpose);
    if (!rcondAbove(data.lu, 1e-12)) return Fault::kSingular;
    if (residual <= tol) return Fault::kNone;
    if (it == max_iterations) break;
    X -= data.lu.solve(data.g);
    iterations = it + 1;
  }
  return Fault::kNotConverged;
}

}  // namespace

TauModel TauModel::load(const std::string& path) { return fromParams(ParamFile::load(path)); }

TauModel TauModel::fromParams(const ParamFile& p) {
  p.requireFormat(kDeviceName, kFormatVersion);
  TauModel m;
  m.kinematics_ = RusLegKinematics::fromParams(p);
  m.torque_limit_ = p.vector<6>("limits/joint_torque", 1e-3, 100.0);
  m.encoder_counts_ = static_cast<int>(p.integer("encoder/counts_per_turn", 16, 1 << 24));
  m.servo_period_ = p.number("rates/servo_period", 1e-5, 0.1);
  m.substeps_ = static_cast<int>(p.integer("rates/simulation_substeps", 1, 1000));
  m.workspace_half_side_ = p.number("workspace/half_side", 1e-3, 0.5);
  m.workspace_half_angle_ = p.number("workspace/half_angle_deg", 0.0, 60.0) * M_PI / 180.0;
  m.characteristic_length_ = p.number("workspace/characteristic_length", 1e-3, 1.0);
  // The stops bound the workspace (at or outside its faces).
  m.end_stops_.half_side = p.number("end_stops/half_side", m.workspace_half_side_, 0.5);
  m.end_stops_.half_angle = p.number("end_stops/half_angle_deg", m.workspace_half_angle_ * 180.0 / M_PI, 60.0) * M_PI / 180.0;
  m.end_stops_.stiffness = p.number("end_stops/stiffness", 1.0, 1e6);
  m.end_stops_.damping = p.number("end_stops/damping", 0.0, 1e3);
  m.end_stops_.angular_stiffness = p.number("end_stops/angular_stiffness", 1e-3, 1e3);
  m.end_stops_.angular_damping = p.number("end_stops/angular_damping", 0.0, 10.0);
  m.fk_tolerance_ = p.number("forward_kinematics/tolerance", 1e-15, 1e-6);
  m.fk_max_iterations_ = static_cast<int>(p.integer("forward_kinematics/max_iterations", 1, 1000));
  m.gravity_ = Vec3(0.0, 0.0, -p.number("gravity", 0.0, 20.0));
  m.joint_inertia_ = p.vector<6>("inertia/rotor", 0.0, 1.0);
  m.link_mass_ = p.vector<6>("links/mass", 0.0, 10.0);
  m.link_com_radius_ = p.vector<6>("links/com_radius", 0.0, 0.5);
  m.rod_mass_ = p.vector<6>("rods/mass", 0.0, 10.0);
  m.platform_masses_.push_back({p.number("platform/mass", 1e-3, 10.0), p.vector<3>("platform/com", -0.2, 0.2)});
  m.platform_masses_.push_back({p.number("handle/mass", 0.0, 10.0), p.vector<3>("handle/com", -0.3, 0.3)});
  p.rejectUnreadKeys({ParamFile::kBoardSection});
  try {
    m.finalize();
  } catch (const Error& e) {
    p.fail(e.what());
  }
  return m;
}

TauModel::TauModel(std::shared_ptr<const TauKinematics> kinematics, const TauModel& physical) : TauModel(physical) {
  if (!kinematics) throw Error("TauModel: no kinematics given");
  kinematics_ = std::move(kinematics);
  platform_masses_.resize(2);  // drop the previous geometry's rod halves
  finalize();
}

void TauModel::finalize() {
  for (int i = 0; i < 6; ++i) {
    if (link_com_radius_(i) > kinematics_->linkLength(i))
      throw Error("links/com_radius of joint " + std::to_string(i + 1) + " exceeds its link length");
    if (rod_mass_(i) > 0.0) platform_masses_.push_back({0.5 * rod_mass_(i), kinematics_->platformAttachment(i)});
  }
  if (inverse(home_pose_, home_q_) != Fault::kNone)
    throw Error("the home pose (workspace centre) is not reachable with this geometry");
  TauData data(*this);
  const Fault f = forward(home_q_, data);
  if (f != Fault::kNone) throw Error(std::string("forward kinematics fails at the home pose: ") + toString(f));
  if ((data.pose - home_pose_).norm() > 1e-9) throw Error("forward and inverse kinematics disagree at the home pose");
  assembly_mode_sign_ = data.lu.determinant() > 0.0 ? 1.0 : -1.0;
  Vec6 rotor_total = joint_inertia_;
  for (int i = 0; i < 6; ++i) {
    const double L1 = kinematics_->linkLength(i);
    rotor_total(i) += link_mass_(i) * link_com_radius_(i) * link_com_radius_(i) + 0.5 * rod_mass_(i) * L1 * L1;
    if (!(rotor_total(i) > 0.0)) throw Error("joint " + std::to_string(i + 1) + " has zero inertia");
  }
  joint_inertia_ = rotor_total;
}

double TauModel::encoderResolution() const noexcept { return 2.0 * M_PI / encoder_counts_; }

Fault TauModel::forward(const Vec6& q, TauData& data) const noexcept {
  if (!q.allFinite()) return Fault::kNonFiniteInput;
  Vec6 X = data.pose.allFinite() ? data.pose : home_pose_;
  double residual = 0.0;
  int iterations = 0;
  // The closure equations have several solutions (assembly modes); Newton from a far warm start can
  // land on another one. The device's own is the one the closed-form inverse maps back to q.
  auto solveOwnMode = [&]() {
    Fault r = solvePose(*kinematics_, q, fk_tolerance_, fk_max_iterations_, X, data, residual, iterations);
    if (r == Fault::kNone) {
      // Modes are separated by the singularities of dg/dX, so the device's own keeps the sign of
      // det(dg/dX) it has at home; the inverse's leg branches must also map the pose back to q.
      // The round trip is as exact as the pose: Newton stops at a closure residual <= fk_tolerance_
      // (m), which moves the joints by ~residual / lever (~0.1 m); 1e3 rad/m covers that with margin
      // and stays far below the distance between assembly modes (tenths of a radian). A fixed
      // 1e-9 rad refused every pose for tolerances above ~1e-8 m (tools/bench/numerics_bench.cpp).
      const double round_trip = std::max(1e-9, 1e3 * fk_tolerance_);
      Vec6 q_back;
      const bool other_mode = assembly_mode_sign_ != 0.0 && data.lu.determinant() * assembly_mode_sign_ <= 0.0;
      if (other_mode || kinematics_->inverse(X, q_back) != Fault::kNone ||
          !((q_back - q).cwiseAbs().maxCoeff() <= round_trip))
        r = Fault::kOutOfRange;
    }
    return r;
  };
  Fault f = solveOwnMode();
  if (f != Fault::kNone && f != Fault::kNonFiniteInput) {
    // A poor warm start (after a jump in q) gets one retry from the workspace centre.
    X = home_pose_;
    f = solveOwnMode();
  }
  data.fk_residual = residual;
  data.fk_iterations = iterations;
  if (f != Fault::kNone) return f;
  data.pose = X;
  data.J.noalias() = -data.lu.solve(data.dg_dq);
  return data.J.allFinite() ? Fault::kNone : Fault::kSingular;
}

void TauModel::forward(const Vec6& q, Vec6& x) const noexcept {
  TauData data(*this);
  if (forward(q, data) == Fault::kNone) x = data.pose;
  else x.setConstant(std::numeric_limits<double>::quiet_NaN());
}

void TauModel::jacobian(const Vec6& q, Mat6& J) const noexcept {
  TauData data(*this);
  if (forward(q, data) == Fault::kNone) J = data.J;
  else J.setConstant(std::numeric_limits<double>::quiet_NaN());
}

void TauModel::computeGravity(const Vec6& q, TauData& data) const noexcept {
  const PoseRotation rot(data.pose);
  Vec6 gen = Vec6::Zero();  // generalized force conjugate to X that holds the platform masses
  for (const PointMass& pm : platform_masses_) gen.noalias() -= pm.mass * rot.pointJacobian(pm.body_point).transpose() * gravity_;
  data.gravity.noalias() = data.J.transpose() * gen;
  for (int i = 0; i < 6; ++i) {
    Vec3 point, dpoint;
    const double L1 = kinematics_->linkLength(i);
    kinematics_->linkPoint(i, q(i), link_com_radius_(i), point, dpoint);
    data.gravity(i) -= link_mass_(i) * dpoint.dot(gravity_);
    kinematics_->linkPoint(i, q(i), L1, point, dpoint);
    data.gravity(i) -= 0.5 * rod_mass_(i) * dpoint.dot(gravity_);
  }
}

Fault TauModel::computeDynamicsTerms(const Vec6& q, const Vec6& qd, TauData& data) const noexcept {
  const PoseRotation rot(data.pose);
  data.M = joint_inertia_.asDiagonal();
  for (const PointMass& pm : platform_masses_) {
    const Mat<3, 6> T = rot.pointJacobian(pm.body_point) * data.J;
    data.M.noalias() += pm.mass * T.transpose() * T;
  }
  computeGravity(q, data);
  data.bias.setZero();
  const double speed = qd.cwiseAbs().maxCoeff();
  if (!std::isfinite(speed)) return Fault::kNonFiniteInput;
  if (speed < 1e-12) return Fault::kNone;
  // Velocity-product acceleration (qdd = 0) of every platform point. Differentiating the closure
  // g(X(t), q(t)) = 0 twice gives dg/dX X'' = -D2g[v, v] along v = (X', q') = (J qd, qd); D2g[v, v]
  // is a central second difference of g along the line through (X, q) in direction v. g vanishes
  // there to first order (v is tangent to the closure), so the difference loses no digits:
  // truncation O(h^2), rounding ~1e-17 m / h^2. dg/dX is factorized in data.lu by forward().
  const double h = 1e-3 / speed;  // joint step of at most 1 mrad
  const Vec6 Xd = data.J * qd;
  Vec6 g_plus, g_minus;
  Mat6 dg_dpose, dg_dq;  // unused partial derivatives
  kinematics_->constraints(data.pose + h * Xd, q + h * qd, g_plus, dg_dpose, dg_dq);
  kinematics_->constraints(data.pose - h * Xd, q - h * qd, g_minus, dg_dpose, dg_dq);
  const double inv_h2 = 1.0 / (h * h);
  const Vec6 Xdd = -data.lu.solve((g_plus - 2.0 * data.g + g_minus) * inv_h2);
  if (!Xdd.allFinite()) return Fault::kNonFiniteResult;
  // A point x = p + R(angles) c: x'' = S X'' + the second derivative of R c along the angle rates.
  const PoseRotation rp(data.pose + h * Xd), rm(data.pose - h * Xd);
  for (const PointMass& pm : platform_masses_) {
    const Mat<3, 6> S = rot.pointJacobian(pm.body_point);
    const Vec3 accel = S * Xdd + (rp.R * pm.body_point - 2.0 * (rot.R * pm.body_point) + rm.R * pm.body_point) * inv_h2;
    data.bias.noalias() += pm.mass * (S * data.J).transpose() * accel;
  }
  return Fault::kNone;
}

Fault TauModel::forwardDynamics(const Vec6& q, const Vec6& qd, const Vec6& tau, const Vec3& tool_force, TauData& data,
                                Vec6& qdd) const noexcept {
  if (!qd.allFinite() || !tau.allFinite() || !tool_force.allFinite()) return Fault::kNonFiniteInput;
  Fault f = forward(q, data);
  if (f == Fault::kNone) f = computeDynamicsTerms(q, qd, data);
  if (f != Fault::kNone) {
    qdd.setZero();
    return f;
  }
  const Vec6 rhs = tau + data.J.topRows<3>().transpose() * tool_force - data.bias - data.gravity;
  qdd = data.M.llt().solve(rhs);
  return qdd.allFinite() ? Fault::kNone : Fault::kNonFiniteResult;
}

Fault TauModel::stateDerivative(const Vec<12>& x, const Vec6& tau, TauData& data, Vec<12>& xdot) const noexcept {
  Vec6 qdd;
  const Fault f = forwardDynamics(x.tail<6>(), x.head<6>(), tau, Vec3::Zero(), data, qdd);
  xdot.head<6>() = qdd;
  xdot.tail<6>() = x.head<6>();
  return f;
}

double TauModel::scaledConditionNumber(const Mat6& J, double characteristic_length) {
  Mat6 Js = J;
  Js.bottomRows<3>() *= characteristic_length;
  const Vec6 s = Eigen::JacobiSVD<Mat6>(Js).singularValues();
  return s(5) > 0.0 ? s(0) / s(5) : std::numeric_limits<double>::infinity();
}

}  // namespace uhaptics
