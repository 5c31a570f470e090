#include "uhaptics/renderers/exo_finger_policy.hpp"

#include <algorithm>
#include <cmath>

#include "uhaptics/core/finite_difference.hpp"
#include "uhaptics/core/regularized_solve.hpp"

namespace uhaptics {
namespace {

constexpr int kGrid = 21;  // samples per finger joint when surveying the working range

}  // namespace

ExoFingerPolicy::ExoFingerPolicy(Model model, const Options& options, FigureRecorder& figures)
    : model_(std::make_unique<const Model>(std::move(model))), figures_(figures), options_(options), method_(options.method) {
  if (!(options.coupling_stiffness > 0.0) || !std::isfinite(options.coupling_stiffness) || !(options.servo_period > 0.0)) {
    throw Error("exo finger policy: coupling_stiffness and servo_period must be finite and > 0");
  }
  const Model& m = *model_;
  // Survey the working range: fingertip extent (workspace), actuator lever |d x / d l_x| (for Z_q)
  // and fingertip displacement per actuator length (for the force the device can show).
  Vec2 lo = Vec2::Constant(1e9), hi = Vec2::Constant(-1e9);
  double lever_sq = 0.0, tip_per_length = 0.0, tip_lever_sq = 0.0;
  int samples = 0;
  for (int i = 0; i < kGrid; ++i) {
    for (int j = 0; j < kGrid; ++j) {
      const Model::TaskVector x =
          m.taskLower() + (m.taskUpper() - m.taskLower()).cwiseProduct(Vec2(i / (kGrid - 1.0), j / (kGrid - 1.0)));
      Model::JointVector q;
      if (!m.inverse(x, q)) continue;
      const Vec2 tip = fingertip(x);
      lo = lo.cwiseMin(tip);
      hi = hi.cwiseMax(tip);
      Model::Jacobian J;
      m.jacobian(q, J);
      const Mat2 Jtip = centralDifferenceJacobian([&](const Vec2& y) { return fingertip(y); }, x);
      lever_sq += J.col(0).squaredNorm();
      tip_per_length += (Jtip * J.col(0)).norm();
      tip_lever_sq += 0.5 * Jtip.squaredNorm();
      ++samples;
    }
  }
  if (samples == 0) throw Error("exo finger: no configuration of the working range assembles");
  lever_sq_ = lever_sq / samples;
  tip_per_length /= samples;
  tip_lever_sq_ = tip_lever_sq / samples;
  centre_ = 0.5 * (lo + hi);
  workspace_radius_ = 0.5 * (hi - lo).minCoeff();
  // Virtual work: F_tip |d tip| = F_act |d l_x|, on average over the working range.
  fingertip_force_ = m.effortLimits()(0) / tip_per_length;
  setCouplingStiffness(options.coupling_stiffness);

  fig_contact_ticks_ = figures_.declareFigure("proxy_contact_ticks", FigureKind::kCount);
  fig_proxy_distance_ = figures_.declareFigure("max_proxy_distance_mm", FigureKind::kMaximum);
  fig_actuator_force_ = figures_.declareFigure("max_actuator_force_N", FigureKind::kMaximum);
  fig_solves_ = figures_.declareFigure("proxy_solves", FigureKind::kCount);
  fig_active_impedance_ = figures_.declareFigure("active_impedance_ticks", FigureKind::kCount);
}

void ExoFingerPolicy::setCouplingStiffness(double stiffness) {
  if (!(stiffness > 0.0) || !std::isfinite(stiffness)) throw Error("exo finger policy: coupling_stiffness must be finite and > 0");
  coupling_stiffness_ = stiffness;
  fingertip_stiffness_ = stiffness / tip_lever_sq_;
  actuator_stiffness_ = stiffness * lever_sq_;  // Z_x seen at l_x
  UnderactuatedGains<Model> gains;
  gains.Zx = stiffness * Mat2::Identity();
  gains.Zq = Model::ActuatorVector::Constant(actuator_stiffness_).asDiagonal();
  gains.force_limit = model_->effortLimits();
  subspace_ = std::make_unique<NonlinearSubspaceRenderer<Model>>(*model_, gains);
  standard_ = std::make_unique<StandardRenderer<Model>>(*model_, gains);
  nullspace_ = std::make_unique<NullSpaceRenderer<Model>>(*model_, gains);
}

std::string ExoFingerPolicy::name() const {
  switch (method_) {
    case Method::kStandard: return StandardRenderer<Model>::kName;
    case Method::kNullSpace: return NullSpaceRenderer<Model>::kName;
    case Method::kSubspaceProxy: break;
  }
  return NonlinearSubspaceRenderer<Model>::kName;
}

Vec2 ExoFingerPolicy::fingertip(const Model::TaskVector& x) const noexcept {
  ExoFingerPoints points;
  model_->points(x, points);
  return points.fingertip;
}

Mat2 ExoFingerPolicy::fingertipJacobian(const Model::TaskVector& x) const noexcept {
  // fingertip = L_p u(q_MCP) + L_m u(q_MCP + q_PIP), u(a) = (cos a, sin a): differentiated in closed form.
  const ExoFingerGeometry& g = model_->geometry();
  const double a = x(0), b = x(0) + x(1);
  const Vec2 distal = g.middle_length * Vec2(-std::sin(b), std::cos(b));
  Mat2 J;
  J.col(0) = g.proximal_length * Vec2(-std::sin(a), std::cos(a)) + distal;
  J.col(1) = distal;
  return J;
}

void ExoFingerPolicy::reset(int) {
  subspace_->reset();
  actuator_.setZero();
}

void ExoFingerPolicy::endSession() noexcept {
  actuator_.setZero();
  finger_torque_.setZero();
}

void ExoFingerPolicy::sense(const SensedJoints& reading, SensedState& state) noexcept {
  model_->forward(Eigen::Map<const Model::JointVector>(reading.positions), data_);
  // Hand frame (x distal) -> device y-z plane, see the class comment.
  const Vec3 position = planarToDevice(data_.points.fingertip - centre_);
  state.linear_velocity = reading.first ? Vec3::Zero() : ((position - last_position_) / options_.servo_period).eval();
  state.position = last_position_ = position;
  state.joints = data_.q;  // l_x [m], q_B [rad]
}

Fault ExoFingerPolicy::render(const SceneInput& input, double* efforts) noexcept {
  const double Zx = coupling_stiffness_;
  // The proxy pull in the finger plane (device y, z) -> hand frame -> finger-joint torque.
  const Vec2 f_hand = deviceToPlanar(input.force);
  const bool pulled = !f_hand.isZero(0.0);
  Mat2 Jtip = Mat2::Zero();  // d fingertip / d x, hand frame; only with a command
  if (pulled || !finger_torque_.isZero(0.0)) Jtip = fingertipJacobian(data_.x);
  Model::TaskVector x_proxy = data_.x;
  if (pulled) x_proxy += (Jtip.transpose() * f_hand) / Zx;
  x_proxy += finger_torque_ / Zx;  // multi-point tools' joint torque
  const double scene = (data_.J.transpose() * (Zx * (x_proxy - data_.x)))(0);  // S J^T Z_x (x_p - x)
  scene_actuator_force_ = std::isfinite(scene) ? scene : 0.0;
  // The renderer solves for the subspace proxy exactly when it has a proxy off the probe to render
  // and none of its input checks fails (the same checks, on the same model evaluations of q): in
  // free space (no force, no joint torque) the proxy is the probe and every solve is skipped.
  const bool solves = !(x_proxy - data_.x).isZero(0.0) && x_proxy.allFinite() && data_.q.allFinite() &&
                      data_.in_range && data_.x.allFinite() && data_.J.allFinite();
  // The sensed state's kinematics (sense()) are the renderer's: it evaluates the model only to solve.
  Fault fault = Fault::kNone;
  switch (method_) {
    case Method::kStandard:
      fault = standard_->tick(data_.q, x_proxy, data_.x, data_.J, data_.in_range, actuator_);
      break;
    case Method::kNullSpace:
      fault = nullspace_->tick(data_.q, x_proxy, data_.x, data_.J, data_.in_range, actuator_);
      break;
    case Method::kSubspaceProxy:
      fault = subspace_->tick(data_.q, x_proxy, data_.x, data_.J, data_.in_range, actuator_);
      break;
  }
  if (solves) {
    figures_.count(fig_solves_);
    const double distance = (fingertip(x_proxy) - data_.points.fingertip).norm();  // probe f(q) to proxy
    figures_.observeMaximum(fig_proxy_distance_, 1e3 * distance);
    // The scene's pull as one fingertip force: the joint torque it asks for, Z_x (x_p - x), through
    // J_tip^-T (the Cartesian force itself when only that channel is used).
    const Vec2 pull = regularizedSolve(Jtip.transpose(), Zx * (x_proxy - data_.x));
    if (fault == Fault::kNone && pull.norm() > kContactThreshold) {
      figures_.count(fig_contact_ticks_);
      // Passivity of what the method displays here: the symmetric part of d tau / d q must not
      // have a positive eigenvalue (relative to the impedance's size: rounding is not activity).
      const Mat2 Z = method_ == Method::kStandard    ? standard_->displayedImpedance()
                     : method_ == Method::kNullSpace ? nullspace_->displayedImpedance()
                                                     : subspace_->displayedImpedance();
      const Mat2 symmetric = 0.5 * (Z + Z.transpose());
      const double trace = symmetric.trace(), det = symmetric.determinant();
      const double largest = 0.5 * trace + std::sqrt(std::max(0.0, 0.25 * trace * trace - det));
      if (largest > 1e-9 * Z.norm()) figures_.count(fig_active_impedance_);
    }
  }
  figures_.observeMaximum(fig_actuator_force_, std::abs(actuator_(0)));
  Eigen::Map<Model::ActuatorVector> out(efforts);
  out = actuator_;
  return fault;
}

}  // namespace uhaptics
