#include "uhaptics/models/exo_finger_model.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <sstream>

#include "uhaptics/models/param_file.hpp"

namespace uhaptics {

namespace {
constexpr double kPi = 3.14159265358979323846;

Vec2 unit(double angle) noexcept { return {std::cos(angle), std::sin(angle)}; }
Vec2 rotate(double angle, const Vec2& v) noexcept {
  const double c = std::cos(angle), s = std::sin(angle);
  return {c * v.x() - s * v.y(), s * v.x() + c * v.y()};
}
double cross(const Vec2& a, const Vec2& b) noexcept { return a.x() * b.y() - a.y() * b.x(); }
// acos continued by clamping: beyond the assembly region the closure is held at its limit.
double clampedAcos(double c) noexcept { return std::acos(std::clamp(c, -1.0, 1.0)); }
// The representative of angle nearest to centre (angles from atan2 may come out 2 pi away). Within
// pi of centre std::remainder returns its argument exactly, so the library call is needed only
// beyond that.
double wrapNear(double angle, double centre) noexcept {
  const double offset = angle - centre;
  if (std::abs(offset) <= kPi) return centre + offset;
  return centre + std::remainder(offset, 2.0 * kPi);
}
}  // namespace

ExoFingerModel ExoFingerModel::load(const std::string& path) { return fromParams(ParamFile::load(path)); }

ExoFingerModel ExoFingerModel::fromParams(const ParamFile& p) {
  p.requireFormat(kDeviceName, kFormatVersion);
  ExoFingerModel m;
  m.origin_ = p.origin();
  auto& g = m.geometry_;
  // Bounds: physically sensible for a finger module (mm to a few cm), wide enough for any adult hand.
  g.proximal_length = p.number("finger/proximal_length", 0.02, 0.08);
  g.middle_length = p.number("finger/middle_length", 0.01, 0.06);
  const Vec2 mcp_range = p.vector<2>("finger/mcp_range", -0.5, 2.0);
  const Vec2 pip_range = p.vector<2>("finger/pip_range", -0.5, 2.2);
  if (!(mcp_range(0) < mcp_range(1))) p.fail("'finger/mcp_range' must be increasing [low, high]");
  if (!(pip_range(0) < pip_range(1))) p.fail("'finger/pip_range' must be increasing [low, high]");
  m.task_lower_ << mcp_range(0), pip_range(0);
  m.task_upper_ << mcp_range(1), pip_range(1);

  g.rocker_pivot = p.vector<2>("linkage/rocker_pivot", -0.1, 0.1);
  g.rocker_length = p.number("linkage/rocker_length", 0.002, 0.1);
  g.coupler_length = p.number("linkage/coupler_length", 0.002, 0.1);
  g.output_crank_length = p.number("linkage/output_crank_length", 0.002, 0.1);
  g.output_crank_angle = p.number("linkage/output_crank_angle", -2.0 * kPi, 2.0 * kPi);
  g.actuator_arm_length = p.number("linkage/actuator_arm_length", 0.002, 0.1);
  g.actuator_arm_angle = p.number("linkage/actuator_arm_angle", -2.0 * kPi, 2.0 * kPi);
  g.actuator_base = p.vector<2>("linkage/actuator_base", -0.3, 0.3);
  if (g.actuator_base.norm() < 0.01) p.fail("'linkage/actuator_base' must be at least 10 mm from the MCP axis");
  m.base_angle_ = std::atan2(g.actuator_base.y(), g.actuator_base.x());
  m.base_norm_ = g.actuator_base.norm();
  m.base_squared_norm_ = g.actuator_base.squaredNorm();
  const long mode = p.integer("linkage/four_bar_mode", -1, 1);
  if (mode == 0) p.fail("'linkage/four_bar_mode' must be +1 or -1 (the four-bar's assembly mode)");
  m.rocker_branch_ = static_cast<double>(mode);

  const double retracted = p.number("actuator/retracted_length", 0.01, 0.5);
  const double stroke = p.number("actuator/stroke", 0.001, 0.3);
  m.effort_limits_(0) = p.number("actuator/force_limit", 0.1, 1000.0);
  m.backlash_ = p.numberOr("actuator/backlash", 0.0, 0.0, 0.01);
  m.board_rate_hz_ = p.number("rates/board_rate_hz", 1.0, 100000.0);
  m.host_rate_hz_ = p.number("rates/host_rate_hz", 1.0, 100000.0);
  m.force_loop_tau_ = p.number("rates/force_loop_time_constant", 0.0, 1.0);
  p.rejectUnreadKeys({ParamFile::kBoardSection, ParamFile::kStabilitySection});

  // Assembly modes of the forward closures: the ones that reproduce the middle of the range.
  const TaskVector mid = 0.5 * (m.task_lower_ + m.task_upper_);
  const double phi_mid = m.rockerFromPip(mid(1));
  m.pip_branch_ = 1.0;
  const double err_plus = std::abs(m.pipFromRocker(phi_mid) - mid(1));
  m.pip_branch_ = -1.0;
  if (std::abs(m.pipFromRocker(phi_mid) - mid(1)) > err_plus) m.pip_branch_ = 1.0;
  const double l_mid = m.actuatorLength(mid(0), phi_mid);
  m.mcp_branch_ = 1.0;
  const double mcp_plus = std::abs(m.mcpFromActuator(l_mid, phi_mid) - mid(0));
  m.mcp_branch_ = -1.0;
  if (std::abs(m.mcpFromActuator(l_mid, phi_mid) - mid(0)) > mcp_plus) m.mcp_branch_ = 1.0;

  // The design must assemble, round-trip, stay inside the stroke and keep a nonsingular Jacobian
  // over the whole working range; a coarse grid here (tests use a dense one).
  m.joint_limits_.lower << retracted, 1e300;
  m.joint_limits_.upper << retracted + stroke, -1e300;
  constexpr int kGrid = 41;
  double det_sign = 0.0;
  for (int i = 0; i < kGrid; ++i) {
    for (int j = 0; j < kGrid; ++j) {
      const TaskVector x = m.task_lower_ + (m.task_upper_ - m.task_lower_).cwiseProduct(
                                               TaskVector(double(i) / (kGrid - 1), double(j) / (kGrid - 1)));
      JointVector q;
      std::ostringstream where;
      where << "at MCP " << x(0) * 180.0 / kPi << " deg, PIP " << x(1) * 180.0 / kPi << " deg";
      if (!m.inverse(x, q)) p.fail("the linkage does not assemble " + where.str() + "; check 'linkage/*'");
      if (q(0) < retracted - 1e-9 || q(0) > retracted + stroke + 1e-9) {
        std::ostringstream msg;
        msg << "the working range needs an actuator length of " << q(0) * 1000.0 << " mm " << where.str()
            << ", outside the stroke [" << retracted * 1000.0 << ", " << (retracted + stroke) * 1000.0
            << "] mm; check 'actuator/retracted_length', 'actuator/stroke' and 'linkage/actuator_base'";
        p.fail(msg.str());
      }
      TaskVector back;
      m.forward(q, back);
      if ((back - x).cwiseAbs().maxCoeff() > 1e-9)
        p.fail("the linkage's forward and inverse kinematics disagree " + where.str() +
               " (a dead point inside the working range?); check 'linkage/*'");
      Jacobian J;
      m.jacobian(q, J);
      const double det = J.determinant();
      if (!std::isfinite(det) || det == 0.0 || (det_sign != 0.0 && det * det_sign <= 0.0))
        p.fail("the linkage's Jacobian is singular " + where.str() + "; check 'linkage/*'");
      det_sign = det > 0.0 ? 1.0 : -1.0;
      m.joint_limits_.lower(1) = std::min(m.joint_limits_.lower(1), q(1));
      m.joint_limits_.upper(1) = std::max(m.joint_limits_.upper(1), q(1));
    }
  }
  return m;
}

Vec2 ExoFingerModel::actuatorPin(double phi) const noexcept {
  return geometry_.rocker_pivot + geometry_.actuator_arm_length * unit(phi + geometry_.actuator_arm_angle);
}

double ExoFingerModel::rockerFromPip(double pip) const noexcept {
  const auto& g = geometry_;
  const Vec2 pip_axis(g.proximal_length, 0.0);
  const Vec2 w = pip_axis + g.output_crank_length * unit(pip + g.output_crank_angle) - g.rocker_pivot;
  const double r = w.norm();
  const double k = (w.squaredNorm() + g.rocker_length * g.rocker_length - g.coupler_length * g.coupler_length) /
                   (2.0 * g.rocker_length * r);
  return std::atan2(w.y(), w.x()) + rocker_branch_ * clampedAcos(k);
}

double ExoFingerModel::pipFromRocker(double phi) const noexcept {
  const auto& g = geometry_;
  const Vec2 pip_axis(g.proximal_length, 0.0);
  const Vec2 w = pip_axis - g.rocker_pivot - g.rocker_length * unit(phi);
  const double d = g.output_crank_length;
  const double k = (g.coupler_length * g.coupler_length - w.squaredNorm() - d * d) / (2.0 * d * w.norm());
  const double psi = std::atan2(w.y(), w.x()) + pip_branch_ * clampedAcos(k);
  return wrapNear(psi - g.output_crank_angle, 0.5 * (task_lower_(1) + task_upper_(1)));
}

double ExoFingerModel::actuatorLength(double mcp, double phi) const noexcept {
  return (rotate(mcp, actuatorPin(phi)) - geometry_.actuator_base).norm();
}

double ExoFingerModel::mcpFromActuator(double l, double phi) const noexcept {
  const Vec2 C = actuatorPin(phi);
  // |R C - A|^2 = l^2  <=>  A . R C = |A||C| cos(mcp + angle(C) - angle(A)) = (|C|^2 + |A|^2 - l^2) / 2
  // (A's norm and angle are constants of the geometry, computed at load).
  const double k = (C.squaredNorm() + base_squared_norm_ - l * l) / (2.0 * base_norm_ * C.norm());
  const double mcp = base_angle_ - std::atan2(C.y(), C.x()) + mcp_branch_ * clampedAcos(k);
  return wrapNear(mcp, 0.5 * (task_lower_(0) + task_upper_(0)));
}

void ExoFingerModel::forward(const JointVector& q, TaskVector& x) const noexcept {
  x(1) = pipFromRocker(q(1));
  x(0) = mcpFromActuator(q(0), q(1));
}

void ExoFingerModel::jacobian(const JointVector& q, Jacobian& J) const noexcept {
  TaskVector x;
  forward(q, x);
  jacobian(q, x, J);
}

void ExoFingerModel::jacobian(const JointVector& q, const TaskVector& x, Jacobian& J) const noexcept {
  const auto& g = geometry_;
  const double phi = q(1);
  const double l = q(0);
  // Each angle's sine and cosine once: unit() and unitDerivative() of the same angle share them.
  const Vec2 u_phi = unit(phi);
  const Vec2 du_phi(-u_phi.y(), u_phi.x());
  // PIP row, implicit differentiation of |E - D|^2 = c^2 with D = B + a u(phi), E = P + d u(psi).
  const double psi = x(1) + g.output_crank_angle;
  const Vec2 u_psi = unit(psi);
  const Vec2 du_psi(-u_psi.y(), u_psi.x());
  const Vec2 D = g.rocker_pivot + g.rocker_length * u_phi;
  const Vec2 E = Vec2(g.proximal_length, 0.0) + g.output_crank_length * u_psi;
  const Vec2 e = E - D;
  const double dpsi_dphi = (g.rocker_length * e.dot(du_phi)) / (g.output_crank_length * e.dot(du_psi));
  // MCP row, implicit differentiation of |R(mcp) C(phi) - A|^2 = l^2.
  const double mcp = x(0);
  const double c = std::cos(mcp), s = std::sin(mcp);
  const auto rotated = [c, s](const Vec2& v) { return Vec2(c * v.x() - s * v.y(), s * v.x() + c * v.y()); };
  const Vec2 u_arm = unit(phi + g.actuator_arm_angle);
  const Vec2 RC = rotated(g.rocker_pivot + g.actuator_arm_length * u_arm);  // R(mcp) actuatorPin(phi)
  const Vec2 v = RC - g.actuator_base;
  const double dh_dmcp = cross(RC, v);  // v . (d/dmcp R C) = v . perp(R C)
  const Vec2 RdC = rotated(g.actuator_arm_length * Vec2(-u_arm.y(), u_arm.x()));
  J(0, 0) = l / dh_dmcp;
  J(0, 1) = -v.dot(RdC) / dh_dmcp;
  J(1, 0) = 0.0;
  J(1, 1) = dpsi_dphi;
}

bool ExoFingerModel::inverse(const TaskVector& x, JointVector& q) const noexcept {
  const auto& g = geometry_;
  const double phi = rockerFromPip(x(1));
  q(1) = phi;
  q(0) = actuatorLength(x(0), phi);
  // Assembles when the four-bar closes: |E - B| within [|a - c|, a + c].
  const Vec2 E = Vec2(g.proximal_length, 0.0) + g.output_crank_length * unit(x(1) + g.output_crank_angle);
  const double r = (E - g.rocker_pivot).norm();
  return r <= g.rocker_length + g.coupler_length && r >= std::abs(g.rocker_length - g.coupler_length) &&
         q.allFinite();
}

void ExoFingerModel::points(const TaskVector& x, ExoFingerPoints& p) const noexcept {
  const auto& g = geometry_;
  const Vec2 proximal = unit(x(0));
  const Vec2 middle = unit(x(0) + x(1));
  p.mcp.setZero();
  p.pip = g.proximal_length * proximal;
  p.fingertip = p.pip + g.middle_length * middle;
  p.proximal_contact = 0.5 * g.proximal_length * proximal;
  p.middle_contact = p.pip + 0.5 * g.middle_length * middle;
}

bool ExoFingerModel::taskInRange(const TaskVector& x, double tol) const noexcept {
  return x.allFinite() && (x.array() >= task_lower_.array() - tol).all() &&
         (x.array() <= task_upper_.array() + tol).all();
}

bool ExoFingerModel::jointsInRange(const JointVector& q, double tol) const noexcept {
  // Both joints: the rocker too, since outside its range the four-bar can map q_B to an in-range
  // PIP angle on another branch (a reading that is no configuration of this finger).
  return q.allFinite() && !(q.array() < joint_limits_.lower.array() - tol).any() &&
         !(q.array() > joint_limits_.upper.array() + tol).any();
}

bool ExoFingerModel::inWorkingRange(const JointVector& q, double tol) const noexcept {
  if (!jointsInRange(q, tol)) return false;
  TaskVector x;
  forward(q, x);
  return taskInRange(x, tol);
}

void ExoFingerModel::forward(const JointVector& q, ExoFingerData& data) const noexcept {
  // The closures once: the Jacobian and the range check reuse x = f(q).
  data.q = q;
  forward(q, data.x);
  jacobian(q, data.x, data.J);
  points(data.x, data.points);
  data.in_range = jointsInRange(q, 1e-9) && taskInRange(data.x, 1e-9);
}

}  // namespace uhaptics
