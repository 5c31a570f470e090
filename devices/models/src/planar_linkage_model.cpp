#include "uhaptics/models/planar_linkage_model.hpp"

#include <Eigen/LU>
#include <sstream>

#include "uhaptics/core/fault.hpp"
#include "uhaptics/core/regularized_solve.hpp"
#include "uhaptics/models/param_file.hpp"

namespace uhaptics {

namespace {
template <int N>
void requireAll(const Vec<N>& v, double lo, const char* name, const std::string& device) {
  for (int i = 0; i < N; ++i) {
    if (!std::isfinite(v(i)) || !(v(i) >= lo)) {
      std::ostringstream msg;
      msg << device << ": " << name << "[" << i << "] = " << v(i) << " must be finite and >= " << lo;
      throw Error(msg.str());
    }
  }
}
}  // namespace

template <int N>
PlanarLinkageModel<N>::PlanarLinkageModel(Parameters p) : p_(std::move(p)) {
  const std::string& d = p_.device;
  requireAll<N>(p_.link_length, 1e-6, "link_length", d);
  requireAll<N>(p_.link_mass, 0.0, "link_mass", d);
  requireAll<N>(p_.link_inertia, 0.0, "link_inertia", d);
  requireAll<N>(p_.rotor_inertia, 1e-12, "rotor_inertia", d);
  requireAll<N>(p_.viscous_friction, 0.0, "viscous_friction", d);
  requireAll<N>(p_.coulomb_friction, 0.0, "coulomb_friction", d);
  requireAll<N>(p_.torque_limit, 1e-9, "torque_limit", d);
  if (!p_.coupling.allFinite() || !p_.angle_offset.allFinite() || !p_.base.allFinite() || !p_.home.allFinite())
    throw Error(d + ": coupling, angle offsets, base and home must be finite");
  if (!(p_.coulomb_velocity > 0.0) || !std::isfinite(p_.coulomb_velocity))
    throw Error(d + ": coulomb_velocity must be positive");
  if (!p_.joint_limits.valid()) throw Error(d + ": joint limits need a finite map and lower < upper in every row");
  if (!p_.joint_limits.contains(p_.home))
    throw Error(d + ": the home configuration violates the joint limits");
  // Every joint must move some link, or the Jacobian has a zero column everywhere.
  for (int j = 0; j < N; ++j)
    if (p_.coupling.col(j).cwiseAbs().maxCoeff() == 0.0)
      throw Error(d + ": joint " + std::to_string(j) + " moves no link (zero column in coupling)");
  const double det = p_.coupling.determinant();
  coupling_invertible_ = std::isfinite(det) && std::abs(det) > 1e-12;
  if (coupling_invertible_) coupling_inverse_ = p_.coupling.inverse();
  coupling_integer_ = (p_.coupling.array() == p_.coupling.array().round()).all();
}

template <int N>
PlanarLinkageModel<N> PlanarLinkageModel<N>::load(const std::string& path, const std::string& device) {
  return fromParams(ParamFile::load(path), device);
}

template <int N>
PlanarLinkageModel<N> PlanarLinkageModel<N>::fromParams(const ParamFile& f, const std::string& device) {
  f.requireFormat(device, kFormatVersion);
  if (f.integer("joints", N, N) != N) f.fail("wrong number of joints");
  Parameters p;
  p.device = device;
  p.link_length = f.vector<N>("kinematics/link_lengths", 1e-3, 10.0);
  const auto rows = f.numbers("kinematics/coupling", static_cast<std::size_t>(N * N), -10.0, 10.0);
  for (int i = 0; i < N; ++i)
    for (int j = 0; j < N; ++j) p.coupling(i, j) = rows[static_cast<std::size_t>(i * N + j)];
  p.angle_offset = f.vector<N>("kinematics/angle_offsets", -10.0, 10.0);
  p.base = f.vector<2>("kinematics/base_position", -10.0, 10.0);
  p.link_mass = f.vector<N>("dynamics/link_masses", 0.0, 100.0);
  p.link_inertia = f.vector<N>("dynamics/link_inertias", 0.0, 10.0);
  p.rotor_inertia = f.vector<N>("dynamics/rotor_inertias", 1e-12, 10.0);
  p.viscous_friction = f.vector<N>("friction/viscous", 0.0, 100.0);
  p.coulomb_friction = f.vector<N>("friction/coulomb", 0.0, 100.0);
  p.coulomb_velocity = f.number("friction/coulomb_smoothing_velocity", 1e-6, 1.0);
  p.torque_limit = f.vector<N>("actuators/torque_limits", 1e-6, 1000.0);
  p.home = f.vector<N>("configuration/home", -10.0, 10.0);
  if (f.has("limits/joint_limits")) {  // optional: devices without stops omit it
    const auto map = f.numbers("limits/joint_limits/map", static_cast<std::size_t>(N * N), -10.0, 10.0);
    for (int i = 0; i < N; ++i)
      for (int j = 0; j < N; ++j) p.joint_limits.map(i, j) = map[static_cast<std::size_t>(i * N + j)];
    p.joint_limits.lower = f.vector<N>("limits/joint_limits/lower", -10.0, 10.0);
    p.joint_limits.upper = f.vector<N>("limits/joint_limits/upper", -10.0, 10.0);
  }
  f.rejectUnreadKeys({ParamFile::kBoardSection, ParamFile::kStabilitySection});
  try {
    return PlanarLinkageModel(std::move(p));
  } catch (const Error& e) {
    f.fail(e.what());
  }
}

template <int N>
void PlanarLinkageModel<N>::positionAt(const JointVector& c, const JointVector& s, TaskVector& x) const noexcept {
  x = p_.base;
  x(0) += p_.link_length.dot(c);
  x(1) += p_.link_length.dot(s);
}

template <int N>
void PlanarLinkageModel<N>::jacobianAt(const JointVector& c, const JointVector& s, Jacobian& J) const noexcept {
  // Row 0: -sum_i d_i s_i a_ij, row 1: sum_i d_i c_i a_ij.
  J.row(0) = -(p_.link_length.cwiseProduct(s)).transpose() * p_.coupling;
  J.row(1) = (p_.link_length.cwiseProduct(c)).transpose() * p_.coupling;
}

template <int N>
void PlanarLinkageModel<N>::jacobianDerivativeAt(const JointVector& c, const JointVector& s, int k,
                                                 Jacobian& dJ) const noexcept {
  const JointVector w = p_.link_length.cwiseProduct(p_.coupling.col(k));  // d_i a_ik
  dJ.row(0) = -(w.cwiseProduct(c)).transpose() * p_.coupling;
  dJ.row(1) = -(w.cwiseProduct(s)).transpose() * p_.coupling;
}

template <int N>
void PlanarLinkageModel<N>::forward(const JointVector& q, TaskVector& x) const noexcept {
  JointVector c, s;
  linkAngles(q, c, s);
  positionAt(c, s, x);
}

template <int N>
void PlanarLinkageModel<N>::jacobian(const JointVector& q, Jacobian& J) const noexcept {
  JointVector c, s;
  linkAngles(q, c, s);
  jacobianAt(c, s, J);
}

template <int N>
void PlanarLinkageModel<N>::jacobianDerivative(const JointVector& q, int k, Jacobian& dJ) const noexcept {
  JointVector c, s;
  linkAngles(q, c, s);
  jacobianDerivativeAt(c, s, k, dJ);
}

template <int N>
void PlanarLinkageModel<N>::forwardAndJacobian(const JointVector& q, TaskVector& x, Jacobian& J) const noexcept {
  JointVector c, s;
  linkAngles(q, c, s);
  positionAt(c, s, x);
  jacobianAt(c, s, J);
}

template <int N>
void PlanarLinkageModel<N>::jacobianDerivatives(const JointVector& q, std::array<Jacobian, N>& dJ) const noexcept {
  JointVector c, s;
  linkAngles(q, c, s);
  for (int k = 0; k < N; ++k) jacobianDerivativeAt(c, s, k, dJ[static_cast<std::size_t>(k)]);
}

template <int N>
void PlanarLinkageModel<N>::massMatrix(const JointVector& q, MassMatrix& M) const noexcept {
  JointVector c, s;
  linkAngles(q, c, s);
  M = p_.rotor_inertia.asDiagonal();
  Jacobian prefix = Jacobian::Zero();  // sum over links before i of d_l e'(phi_l) a_l^T
  for (int i = 0; i < N; ++i) {
    const Vec2 e_perp(-s(i), c(i));
    const auto a = p_.coupling.row(i);
    const Jacobian Jc = prefix + (0.5 * p_.link_length(i)) * e_perp * a;
    M.noalias() += p_.link_mass(i) * Jc.transpose() * Jc;
    M.noalias() += p_.link_inertia(i) * a.transpose() * a;
    prefix += p_.link_length(i) * e_perp * a;
  }
}

template <int N>
void PlanarLinkageModel<N>::velocityProductTorque(const JointVector& q, const JointVector& qd,
                                                  JointVector& c_out) const noexcept {
  JointVector c, s;
  linkAngles(q, c, s);
  const JointVector omega = p_.coupling * qd;
  c_out.setZero();
  Jacobian prefix = Jacobian::Zero();
  Vec2 accel_prefix = Vec2::Zero();  // centripetal acceleration of the start of link i
  for (int i = 0; i < N; ++i) {
    const Vec2 e(c(i), s(i));
    const Vec2 e_perp(-s(i), c(i));
    const auto a = p_.coupling.row(i);
    const double half = 0.5 * p_.link_length(i);
    const Jacobian Jc = prefix + half * e_perp * a;
    const Vec2 accel = accel_prefix - half * omega(i) * omega(i) * e;
    c_out.noalias() += p_.link_mass(i) * Jc.transpose() * accel;
    prefix += p_.link_length(i) * e_perp * a;
    accel_prefix -= p_.link_length(i) * omega(i) * omega(i) * e;
  }
}

template <int N>
void PlanarLinkageModel<N>::frictionTorque(const JointVector& qd, JointVector& f, JointVector* dfdqd) const noexcept {
  const double v = p_.coulomb_velocity;
  for (int i = 0; i < N; ++i) {
    const double th = std::tanh(qd(i) / v);
    f(i) = p_.viscous_friction(i) * qd(i) + p_.coulomb_friction(i) * th;
    if (dfdqd) (*dfdqd)(i) = p_.viscous_friction(i) + p_.coulomb_friction(i) * (1.0 - th * th) / v;
  }
}

template <int N>
Fault PlanarLinkageModel<N>::inverse(const TaskVector& x, JointVector& q) const noexcept {
  if (!x.allFinite() || !q.allFinite()) return Fault::kNonFiniteInput;
  if ((x - p_.base).norm() > reach() + 1e-9) return Fault::kOutOfRange;
  JointVector qi = q;
  TaskVector xi;
  Jacobian J;
  for (int i = 0; i < 50; ++i) {
    forward(qi, xi);
    const TaskVector dx = x - xi;
    if (dx.norm() < 1e-13) break;
    jacobian(qi, J);
    qi += regularizedSolve(J, dx);
  }
  forward(qi, xi);
  if (!qi.allFinite() || !xi.allFinite()) return Fault::kNonFiniteResult;
  if (!((x - xi).norm() <= 1e-9)) return Fault::kNotConverged;
  q = qi;
  return Fault::kNone;
}

template <int N>
int PlanarLinkageModel<N>::closeLastTwoLinks(const TaskVector& x, const Vec<N - 2>& leading_angles,
                                             std::array<JointVector, 2>& q) const noexcept {
  if (!coupling_invertible_ || !x.allFinite() || !leading_angles.allFinite()) return 0;
  const Vec<N>& d = p_.link_length;
  constexpr int a = N - 2, b = N - 1;  // the two closing links
  Vec<N> phi;
  TaskVector r = x - p_.base;  // from the end of the leading links to x
  for (int i = 0; i < a; ++i) {
    phi(i) = leading_angles(i);
    r -= d(i) * Vec2(std::cos(phi(i)), std::sin(phi(i)));
  }
  const double c = (r.squaredNorm() - d(a) * d(a) - d(b) * d(b)) / (2.0 * d(a) * d(b));  // cos gamma
  if (!(std::abs(c) <= 1.0)) return 0;
  const int count = c == 1.0 ? 1 : 2;
  for (int k = 0; k < count; ++k) {
    const double gamma = (k == 0 ? 1.0 : -1.0) * std::acos(c);
    phi(a) = std::atan2(r(1), r(0)) - std::atan2(d(b) * std::sin(gamma), d(a) + d(b) * std::cos(gamma));
    phi(b) = phi(a) + gamma;
    q[static_cast<std::size_t>(k)] = coupling_inverse_ * (phi - p_.angle_offset);
  }
  return count;
}

template <int N>
void PlanarLinkageModel<N>::nearestEquivalent(const JointVector& q, const JointVector& reference,
                                              JointVector& q_near) const noexcept {
  q_near = q;
  if (!coupling_integer_) return;
  for (int k = 0; k < N; ++k) q_near(k) = reference(k) + std::remainder(q(k) - reference(k), 2.0 * M_PI);
}

template class PlanarLinkageModel<3>;
template class PlanarLinkageModel<4>;

}  // namespace uhaptics
