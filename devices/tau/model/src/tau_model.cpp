#include "uhaptics/models/tau_model.hpp"

#include "uhaptics/core/decompositions.hpp"  // the fixed-size SVDs, compiled once
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
  p.rejectUnreadKeys({ParamFile::kBoardSection, ParamFile::kStabilitySection});
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
  // The platform's lumped masses (platform, handle, rod halves) move as one rigid body: its
  // dynamics need only their total mass and their first and second moments about the tool centre.
  body_mass_ = 0.0;
  body_first_moment_.setZero();
  body_second_moment_.setZero();
  for (const PointMass& pm : platform_masses_) {
    body_mass_ += pm.mass;
    body_first_moment_ += pm.mass * pm.body_point;
    body_second_moment_ += pm.mass * pm.body_point * pm.body_point.transpose();
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
    link_lever_(i) = link_mass_(i) * link_com_radius_(i) + 0.5 * rod_mass_(i) * L1;
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
  // land on another one. The device's own has its det(dg/dX) sign and its chains' branches.
  auto solveOwnMode = [&]() {
    Fault r = solvePose(*kinematics_, q, fk_tolerance_, fk_max_iterations_, X, data, residual, iterations);
    if (r == Fault::kNone) {
      // Modes are separated by the singularities of dg/dX, so the device's own keeps the sign of
      // det(dg/dX) it has at home; and every chain must be on its assembled branch
      // (TauKinematics::onAssembledBranches). Where that is checked by mapping the pose back through
      // the inverse, the round trip is as exact as the pose: Newton stops at a closure residual <= fk_tolerance_
      // (m), which moves the joints by ~residual / lever (~0.1 m); 1e3 rad/m covers that with margin
      // and stays far below the distance between assembly modes (tenths of a radian). A fixed
      // 1e-9 rad refused every pose for tolerances above ~1e-8 m (tools/bench/numerics_bench.cpp).
      const double round_trip = std::max(1e-9, 1e3 * fk_tolerance_);
      const bool other_mode = assembly_mode_sign_ != 0.0 && data.lu.determinant() * assembly_mode_sign_ <= 0.0;
      if (other_mode || !kinematics_->onAssembledBranches(X, q, data.dg_dq, round_trip)) r = Fault::kOutOfRange;
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
  // dg/dq is diagonal (leg i's closure depends on joint i alone): J's columns are dg/dX^-1's,
  // scaled. Solved a column at a time: Eigen's matrix right-hand side takes its blocked path, which
  // for 6x6 costs more than six vector solves.
  for (int i = 0; i < 6; ++i) {
    data.J.col(i) = data.lu.solve(Vec6::Unit(i));
    data.J.col(i) *= -data.dg_dq(i, i);
  }
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

void TauModel::computeGravity(const Vec6& q, TauData& data) const noexcept { computeGravity(q, PoseRotation(data.pose), data); }

void TauModel::computeGravity(const Vec6& q, const PoseRotation& rot, TauData& data) const noexcept {
  // Generalized force conjugate to X that holds the platform's masses: -sum m S_c^T g, with
  // S_c = d(p + R c)/dX = [I, dR_a c, dR_b c, dR_g c] linear in c, i.e. -[M g; (dR_k mu) . g].
  Vec6 gen;
  gen.head<3>() = -body_mass_ * gravity_;
  for (int k = 0; k < 3; ++k) gen(3 + k) = -(rot.dR[k] * body_first_moment_).dot(gravity_);
  data.gravity.noalias() = data.J.transpose() * gen;
  for (int i = 0; i < 6; ++i) {
    // A point at radius r along link i moves r times as fast as the link's unit point: the link's
    // centre of mass and the rod's half-mass at its tip act through one derivative.
    Vec3 point, dpoint;
    kinematics_->linkPoint(i, q(i), 1.0, point, dpoint);
    data.gravity(i) -= link_lever_(i) * dpoint.dot(gravity_);
  }
}

Fault TauModel::computeDynamicsTerms(const Vec6& q, const Vec6& qd, TauData& data) const noexcept {
  const PoseRotation rot(data.pose);
  // The platform's inertia in pose coordinates, sum m S_c^T S_c: [M I, dR_k mu; ., tr(dR_k^T dR_l C)]
  // with mu = sum m c and C = sum m c c^T; then M(q) = rotors + J^T M_X J.
  std::array<Mat3, 3> dRC;
  for (int k = 0; k < 3; ++k) dRC[k].noalias() = rot.dR[k] * body_second_moment_;
  Mat6 MX;
  MX.topLeftCorner<3, 3>() = body_mass_ * Mat3::Identity();
  for (int k = 0; k < 3; ++k) {
    const Vec3 column = rot.dR[k] * body_first_moment_;
    MX.block<3, 1>(0, 3 + k) = column;
    MX.block<1, 3>(3 + k, 0) = column.transpose();
    for (int l = 0; l <= k; ++l) MX(3 + k, 3 + l) = MX(3 + l, 3 + k) = rot.dR[k].cwiseProduct(dRC[l]).sum();
  }
  data.M = joint_inertia_.asDiagonal();
  data.M.noalias() += data.J.transpose() * MX * data.J;
  computeGravity(q, rot, data);
  data.bias.setZero();
  const double speed = qd.cwiseAbs().maxCoeff();
  if (!std::isfinite(speed)) return Fault::kNonFiniteInput;
  if (speed < 1e-12) return Fault::kNone;
  // Velocity-product acceleration (qdd = 0) of every platform point. Differentiating the closure
  // g(X(t), q(t)) = 0 twice gives dg/dX X'' = -g''|_{X''=0, q''=0} along (X', q') = (J qd, qd);
  // dg/dX is factorized in data.lu by forward().
  const Vec6 Xd = data.J * qd;
  Vec6 g_dd;
  kinematics_->closureAcceleration(data.pose, q, Xd, qd, g_dd);
  const Vec6 Xdd = -data.lu.solve(g_dd);
  if (!Xdd.allFinite()) return Fault::kNonFiniteResult;
  // A point x = p + R(angles) c: x'' = S_c X'' + D c, D = R'' at the angle rates. Summed over the
  // masses, sum m S_c^T x'' = M_X X'' + [D mu; tr(dR_k^T D C)].
  const Mat3 D = rot.acceleration(Xd.tail<3>());
  const Mat3 DC = D * body_second_moment_;
  Vec6 body_force = MX * Xdd;
  body_force.head<3>() += D * body_first_moment_;
  for (int k = 0; k < 3; ++k) body_force(3 + k) += rot.dR[k].cwiseProduct(DC).sum();
  data.bias.noalias() = data.J.transpose() * body_force;
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
