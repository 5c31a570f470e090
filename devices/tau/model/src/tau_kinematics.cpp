#include "uhaptics/models/tau_kinematics.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <string>

#include "uhaptics/models/param_file.hpp"

namespace uhaptics {

namespace {
// Rz(gamma) Ry(beta) Rx(alpha), multiplied out.
Mat3 rotationFromTrig(double ca, double sa, double cb, double sb, double cg, double sg) noexcept {
  Mat3 R;
  R << cg * cb, cg * sb * sa - sg * ca, cg * sb * ca + sg * sa,  //
      sg * cb, sg * sb * sa + cg * ca, sg * sb * ca - cg * sa,   //
      -sb, cb * sa, cb * ca;
  return R;
}
}  // namespace

Mat3 PoseRotation::rotation(const Vec6& pose) noexcept {
  return rotationFromTrig(std::cos(pose(3)), std::sin(pose(3)), std::cos(pose(4)), std::sin(pose(4)), std::cos(pose(5)),
                          std::sin(pose(5)));
}

PoseRotation::PoseRotation(const Vec6& pose) noexcept : cos_gamma(std::cos(pose(5))), sin_gamma(std::sin(pose(5))) {
  R = rotationFromTrig(std::cos(pose(3)), std::sin(pose(3)), std::cos(pose(4)), std::sin(pose(4)), cos_gamma, sin_gamma);
  // Each angle turns about its own axis in the product Rz Ry Rx: dRx/dalpha = Rx [e_x]x, so
  // dR/dalpha = R [e_x]x; dR/dgamma = [e_z]x R; dR/dbeta = Rz Ry [e_y]x Rx = [Rz e_y]x R.
  const double cg = cos_gamma, sg = sin_gamma;
  dR[0].col(0).setZero();
  dR[0].col(1) = R.col(2);
  dR[0].col(2) = -R.col(1);
  Mat3 w;  // [Rz e_y]x, Rz e_y = (-sin gamma, cos gamma, 0)
  w << 0.0, 0.0, cg, 0.0, 0.0, sg, -cg, -sg, 0.0;
  dR[1].noalias() = w * R;
  dR[2].row(0) = -R.row(1);
  dR[2].row(1) = R.row(0);
  dR[2].row(2).setZero();
}

Mat3 PoseRotation::acceleration(const Vec3& rates) const noexcept {
  // R' = a' R [e_x]x + b' [w]x R + g' [e_z]x R with w = Rz e_y (dR above); differentiated again
  // with constant rates: R'' = a' R' [e_x]x + b' ([w']x R + [w]x R') + g' [e_z]x R', w' = g' dw/dgamma.
  const auto skew = [](const Vec3& v) {
    Mat3 m;
    m << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
    return m;
  };
  const Mat3 Ex = skew(Vec3::UnitX()), Ez = skew(Vec3::UnitZ());
  const Mat3 W = skew(Vec3(-sin_gamma, cos_gamma, 0.0));
  const Mat3 Wd = skew(rates.z() * Vec3(-cos_gamma, -sin_gamma, 0.0));
  const Mat3 Rd = rates.x() * dR[0] + rates.y() * dR[1] + rates.z() * dR[2];
  return rates.x() * Rd * Ex + rates.y() * (Wd * R + W * Rd) + rates.z() * Ez * Rd;
}

Mat<3, 6> PoseRotation::pointJacobian(const Vec3& c) const noexcept {
  Mat<3, 6> S;
  S.leftCols<3>().setIdentity();
  for (int k = 0; k < 3; ++k) S.col(3 + k) = dR[k] * c;
  return S;
}

RusLegKinematics::RusLegKinematics(const std::array<Leg, 6>& legs) : legs_(legs) {
  for (int i = 0; i < 6; ++i) {
    Leg& l = legs_[i];
    const std::string name = "leg" + std::to_string(i + 1);
    if (!(l.link_length > 0.0) || !(l.rod_length > 0.0)) throw Error("TAU kinematics: " + name + " has a non-positive length");
    if (std::abs(l.axis.norm() - 1.0) > 1e-3 || std::abs(l.zero_direction.norm() - 1.0) > 1e-3)
      throw Error("TAU kinematics: " + name + " axis and zero_direction must be unit vectors");
    if (std::abs(l.axis.dot(l.zero_direction)) > 1e-3)
      throw Error("TAU kinematics: " + name + " zero_direction must be perpendicular to its axis");
    if (l.branch != 1 && l.branch != -1) throw Error("TAU kinematics: " + name + " branch must be +1 or -1");
    l.axis.normalize();
    l.zero_direction = (l.zero_direction - l.zero_direction.dot(l.axis) * l.axis).normalized();
    l.lift_direction = l.axis.cross(l.zero_direction);
  }
}

std::shared_ptr<const RusLegKinematics> RusLegKinematics::fromParams(const ParamFile& params) {
  std::array<Leg, 6> legs;
  for (int i = 0; i < 6; ++i) {
    const std::string k = "legs/leg" + std::to_string(i + 1) + "/";
    Leg& l = legs[i];
    l.base = params.vector<3>(k + "base", -0.5, 0.5);
    l.axis = params.vector<3>(k + "axis", -1.0, 1.0);
    l.zero_direction = params.vector<3>(k + "zero_direction", -1.0, 1.0);
    l.link_length = params.number(k + "link_length", 1e-3, 0.5);
    l.rod_length = params.number(k + "rod_length", 1e-3, 0.5);
    l.platform_point = params.vector<3>(k + "platform_point", -0.2, 0.2);
    l.branch = static_cast<int>(params.integer(k + "branch", -1, 1));
  }
  try {
    return std::make_shared<const RusLegKinematics>(legs);
  } catch (const Error& e) {
    params.fail(e.what());
  }
}

Fault RusLegKinematics::inverse(const Vec6& pose, Vec6& q) const noexcept {
  if (!pose.allFinite()) return Fault::kNonFiniteInput;
  const PoseRotation rot(pose);
  const Vec3 p = pose.head<3>();
  for (int i = 0; i < 6; ++i) {
    const Leg& l = legs_[i];
    const Vec3 d = p + rot.R * l.platform_point - l.base;
    // |d - L1 (cos q u + sin q w)|^2 = L2^2
    const double A = d.dot(l.zero_direction), B = d.dot(l.lift_direction);
    const double C = (d.squaredNorm() + l.link_length * l.link_length - l.rod_length * l.rod_length) / (2.0 * l.link_length);
    const double rho = std::hypot(A, B);
    // Margin keeps the leg away from the fully stretched/folded (singular) configuration.
    if (!(rho > 0.0) || std::abs(C) > rho * (1.0 - 1e-9)) return Fault::kOutOfRange;
    q(i) = std::atan2(B, A) + l.branch * std::acos(C / rho);
    if (q(i) > M_PI) q(i) -= 2.0 * M_PI;
    if (q(i) < -M_PI) q(i) += 2.0 * M_PI;
  }
  return Fault::kNone;
}

void RusLegKinematics::constraints(const Vec6& pose, const Vec6& q, Vec6& g, Mat6& dg_dpose, Mat6& dg_dq) const noexcept {
  const PoseRotation rot(pose);
  const Vec3 p = pose.head<3>();
  dg_dq.setZero();
  for (int i = 0; i < 6; ++i) {
    const Leg& l = legs_[i];
    const double c = std::cos(q(i)), s = std::sin(q(i));
    const Vec3 tip = l.base + l.link_length * (c * l.zero_direction + s * l.lift_direction);
    const Vec3 dtip = l.link_length * (-s * l.zero_direction + c * l.lift_direction);
    const Vec3 d = p + rot.R * l.platform_point - tip;
    // Scaled so that g is a length error: (|d|^2 - L2^2) / (2 L2) ~ |d| - L2 near the solution.
    const double inv = 1.0 / l.rod_length;
    g(i) = 0.5 * (d.squaredNorm() - l.rod_length * l.rod_length) * inv;
    dg_dpose.row(i) = inv * d.transpose() * rot.pointJacobian(l.platform_point);
    dg_dq(i, i) = -inv * d.dot(dtip);
  }
}

void RusLegKinematics::closure(const Vec6& pose, const Vec6& q, Vec6& g) const noexcept {
  const Mat3 R = PoseRotation::rotation(pose);
  const Vec3 p = pose.head<3>();
  for (int i = 0; i < 6; ++i) {
    const Leg& l = legs_[i];
    const double c = std::cos(q(i)), s = std::sin(q(i));
    const Vec3 d = p + R * l.platform_point - (l.base + l.link_length * (c * l.zero_direction + s * l.lift_direction));
    g(i) = 0.5 * (d.squaredNorm() - l.rod_length * l.rod_length) / l.rod_length;
  }
}

bool RusLegKinematics::onAssembledBranches(const Vec6&, const Vec6&, const Mat6& dg_dq, double) const noexcept {
  // For a fixed pose, leg i's closure is a sinusoid in q_i: with D = platform point - base,
  // A = D.u, B = D.w, rho = hypot(A, B), phi = atan2(B, A), g_i = (|D|^2 + L1^2 - L2^2 - 2 L1 rho
  // cos(q_i - phi)) / (2 L2). Its two zeros are inverse()'s two branches, q_i - phi = +-acos(C/rho),
  // and there dg_i/dq_i = (L1/L2) rho sin(q_i - phi) has the sign of the branch. So the round trip
  // through inverse() reduces to a sign per leg (zero: the two branches meet, a singular leg).
  for (int i = 0; i < 6; ++i)
    if (!(dg_dq(i, i) * legs_[i].branch > 0.0)) return false;
  return true;
}

void RusLegKinematics::closureAcceleration(const Vec6& pose, const Vec6& q, const Vec6& pose_rate, const Vec6& q_rate,
                                           Vec6& g_dd) const noexcept {
  const PoseRotation rot(pose);
  const Mat3 Rd = pose_rate(3) * rot.dR[0] + pose_rate(4) * rot.dR[1] + pose_rate(5) * rot.dR[2];
  const Mat3 Rdd = rot.acceleration(pose_rate.tail<3>());
  for (int i = 0; i < 6; ++i) {
    const Leg& l = legs_[i];
    const double c = std::cos(q(i)), s = std::sin(q(i));
    const Vec3 radial = l.link_length * (c * l.zero_direction + s * l.lift_direction);
    const Vec3 tangential = l.link_length * (-s * l.zero_direction + c * l.lift_direction);
    // d = p + R c_i - tip(q_i); with p'' = 0, angle'' = 0, q'' = 0: tip'' = -radial q'^2.
    const Vec3 d = pose.head<3>() + rot.R * l.platform_point - l.base - radial;
    const Vec3 d_rate = pose_rate.head<3>() + Rd * l.platform_point - tangential * q_rate(i);
    const Vec3 d_acc = Rdd * l.platform_point + radial * (q_rate(i) * q_rate(i));
    g_dd(i) = (d_rate.squaredNorm() + d.dot(d_acc)) / l.rod_length;
  }
}

void TauKinematics::closureAcceleration(const Vec6& pose, const Vec6& q, const Vec6& pose_rate, const Vec6& q_rate,
                                        Vec6& g_dd) const noexcept {
  // g vanishes along the motion to first order, so the difference loses no digits: truncation
  // O(h^2), rounding ~1e-17 m / h^2.
  const double speed = q_rate.cwiseAbs().maxCoeff();
  if (!(speed > 0.0)) {
    g_dd.setZero();
    return;
  }
  const double h = 1e-3 / speed;
  Vec6 g_plus, g_zero, g_minus;
  closure(pose + h * pose_rate, q + h * q_rate, g_plus);
  closure(pose, q, g_zero);
  closure(pose - h * pose_rate, q - h * q_rate, g_minus);
  g_dd = (g_plus - 2.0 * g_zero + g_minus) / (h * h);
}

void RusLegKinematics::linkPoint(int joint, double qj, double radius, Vec3& point, Vec3& dpoint) const noexcept {
  const Leg& l = legs_[joint];
  const double c = std::cos(qj), s = std::sin(qj);
  point = l.base + radius * (c * l.zero_direction + s * l.lift_direction);
  dpoint = radius * (-s * l.zero_direction + c * l.lift_direction);
}

}  // namespace uhaptics
