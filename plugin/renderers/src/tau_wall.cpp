#include "uhaptics/renderers/tau_wall.hpp"

#include <cmath>
#include <string>

#include "uhaptics/core/dare.hpp"
#include "uhaptics/core/limits.hpp"
#include "uhaptics/core/lqr_design.hpp"

namespace uhaptics {

namespace {

struct ControllerDesign {
  LqrWallGains gains;
  MatX discrete_A, discrete_B;  // augmented, discretized plant (for the observer)
};

ControllerDesign designController(const TauModel& model, const Vec6& operating_pose, const LqrWallWeights& w,
                                  const CommandDelayDesign& delay, bool check_preconditions) {
  const int command_delay = delay.samples;
  if (delay.random && command_delay < 1) throw Error("designLqrWall: a random command delay needs samples >= 1");
  if (!(delay.rate_weight >= 0.0) || (delay.rate_weight > 0.0 && !delay.random))
    throw Error("designLqrWall: the input-rate weight must be >= 0 and is for the random-delay design only");
  if (!(w.velocity >= 0 && w.position >= 0 && w.integral > 0 && w.torque > 0))
    throw Error("designLqrWall: weights must be non-negative (integral and torque weights positive)");
  if (command_delay < 0 || command_delay > kMaxCommandDelay)
    throw Error("designLqrWall: command delay must be in [0, " + std::to_string(kMaxCommandDelay) + "] samples");
  ControllerDesign out;
  LqrWallGains& gains = out.gains;
  gains.operating_pose = operating_pose;
  if (model.inverse(operating_pose, gains.operating_joints) != Fault::kNone)
    throw Error("designLqrWall: the operating pose is outside the reachable workspace");
  TauData data(model);
  data.pose = operating_pose;
  if (model.forward(gains.operating_joints, data) != Fault::kNone)
    throw Error("designLqrWall: forward kinematics fails at the operating pose (singular configuration)");
  model.computeGravity(gains.operating_joints, data);

  LqrDesignRequest req;
  req.dynamics = [&model, &data](const VecX& x, const VecX& u, VecX& xdot) {
    Vec<12> xd;
    if (model.stateDerivative(x, u, data, xd) != Fault::kNone) xd.setConstant(std::nan(""));
    xdot = xd;
  };
  req.x0 = VecX::Zero(12);
  req.x0.tail(6) = gains.operating_joints;
  req.u0 = data.gravity;
  req.C = MatX::Zero(6, 12);
  req.C.rightCols(6).setIdentity();
  VecX q_diag(18);
  q_diag << VecX::Constant(6, w.velocity), VecX::Constant(6, w.position), VecX::Constant(6, w.integral);
  req.Q = q_diag.asDiagonal();
  req.R = MatX::Identity(6, 6) * w.torque;
  req.period = model.servoPeriod();
  req.input_delay_samples = command_delay;
  req.random_input_delay = delay.random;
  if (delay.rate_weight > 0.0) req.input_rate_weight = MatX::Identity(6, 6) * delay.rate_weight;
  req.dare.check_preconditions = check_preconditions;
  const LqrDesign d = designLqrWithIntegrators(req);
  gains.Kc = d.Kc;
  gains.Ki = d.Ki;
  gains.command_delay = command_delay;
  gains.random_command_delay = delay.random;
  gains.rate_weight = delay.rate_weight;
  gains.ms_spectral_radius = d.random.mean_square_spectral_radius;
  gains.Kd.leftCols(6 * command_delay) = d.Kd;
  Eigen::PartialPivLU<Mat6> lu(gains.Ki);
  if (!(lu.rcond() > 1e-12)) throw Error("designLqrWall: integral gain is singular; bumpless entry impossible");
  gains.Ki_inverse = lu.inverse();
  gains.period = req.period;
  gains.fastest_pole_rad_s = d.fastest_pole_rad_s;
  gains.dare_residual = delay.random ? d.random.relative_residual : d.dare.relative_residual;
  gains.dare_iterations = delay.random ? d.random.iterations : d.dare.iterations;
  gains.operating_torque = data.gravity;
  out.discrete_A = d.discrete.A;
  out.discrete_B = d.discrete.B;
  return out;
}

}  // namespace

LqrWallGains designLqrWall(const TauModel& model, const Vec6& operating_pose, const LqrWallWeights& w,
                           const ObserverNoise& noise, int command_delay) {
  CommandDelayDesign delay;
  delay.samples = command_delay;
  return designLqrWall(model, operating_pose, w, noise, delay);
}

LqrWallGains designLqrWall(const TauModel& model, const Vec6& operating_pose, const LqrWallWeights& w,
                           const ObserverNoise& noise, const CommandDelayDesign& delay) {
  ControllerDesign design = designController(model, operating_pose, w, delay, true);
  LqrWallGains& gains = design.gains;
  const MatX& Ad = design.discrete_A;
  const MatX& Bd = design.discrete_B;

  // Observer on the discretized (non-augmented) plant plus a random-walk input disturbance.
  MatX Ao = MatX::Zero(18, 18), Bo = MatX::Zero(18, 6), C = MatX::Zero(6, 18);
  Ao.topLeftCorner(12, 12) = Ad.topLeftCorner(12, 12);
  Ao.block(0, 12, 12, 6) = Bd.topRows(12);  // d enters like the torque
  Ao.bottomRightCorner(6, 6).setIdentity();
  Bo.topRows(12) = Bd.topRows(12);
  C.block(0, 6, 6, 6).setIdentity();
  const double sq = noise.quantization > 0.0 ? noise.quantization : model.encoderResolution() / std::sqrt(12.0);
  if (!(noise.velocity_process > 0 && noise.disturbance_process > 0 && noise.position_process > 0 && sq > 0))
    throw Error("designLqrWall: observer noise levels must be positive");
  VecX qn(18);
  qn << VecX::Constant(6, noise.velocity_process * noise.velocity_process),
      VecX::Constant(6, noise.position_process * noise.position_process),
      VecX::Constant(6, noise.disturbance_process * noise.disturbance_process);
  // Filter DARE = control DARE of the dual pair (Ao^T, C^T).
  const DareResult kf = solveDare(Ao.transpose(), C.transpose(), MatX(qn.asDiagonal()), MatX::Identity(6, 6) * sq * sq);
  const MatX S = C * kf.P * C.transpose() + MatX::Identity(6, 6) * sq * sq;
  gains.observer_joints = gains.operating_joints;
  gains.observer_torque = gains.operating_torque;
  gains.observer_A = Ao;
  gains.observer_B = Bo;
  gains.observer_gain = kf.P * C.transpose() * S.inverse();
  return gains;
}

LqrWallGains redesignLqrWallGains(const TauModel& model, const Vec6& operating_pose, const LqrWallGains& designed,
                                  const LqrWallWeights& w) {
  // The structure (stabilizability/detectability) does not change with the operating point inside
  // the singularity-free workspace; the residual and closed-loop checks still run on every solve.
  CommandDelayDesign delay;
  delay.samples = designed.command_delay;
  delay.random = designed.random_command_delay;
  delay.rate_weight = designed.rate_weight;
  LqrWallGains gains = designController(model, operating_pose, w, delay, false).gains;
  gains.observer_joints = designed.observer_joints;
  gains.observer_torque = designed.observer_torque;
  gains.observer_A = designed.observer_A;
  gains.observer_B = designed.observer_B;
  gains.observer_gain = designed.observer_gain;
  return gains;
}

void LqrJointRegulator::reset(const Vec6& q_measured) noexcept {
  estimate_.setZero();
  estimate_.segment<6>(6) = q_measured - gains_.observer_joints;
  integral_.setZero();
  for (Vec6& c : commands_) c = gains_.observer_torque;  // at rest, holding gravity
  head_ = 0;
}

Vec6 LqrJointRegulator::inFlightTerm() const noexcept {
  Vec6 term = Vec6::Zero();
  for (int j = 1; j <= gains_.command_delay; ++j)
    term.noalias() += gains_.Kd.middleCols<6>(6 * (j - 1)) * (commanded(j) - gains_.operating_torque);
  return term;
}

void LqrJointRegulator::observe(const Vec6& q_measured, const Vec6* applied) noexcept {
  // The command that drove the plant over the last period: reported by the device, or else the one
  // issued command_delay periods before it (random delay: the expectation, the mean of the commands
  // it may have been).
  // A non-finite report is ignored like a missing one (the tick's own inputs are validated).
  const bool reported = applied && applied->allFinite();
  Vec6 acting = reported ? *applied : commanded(1 + gains_.command_delay);
  if (!reported && gains_.random_command_delay) {
    for (int j = 1; j <= gains_.command_delay; ++j) acting += commanded(j);
    acting /= static_cast<double>(gains_.command_delay + 1);
  }
  const Vec<18> predicted = gains_.observer_A * estimate_ + gains_.observer_B * (acting - gains_.observer_torque);
  const Vec6 innovation = q_measured - gains_.observer_joints - predicted.segment<6>(6);
  estimate_ = predicted + gains_.observer_gain * innovation;
}

// --- front end ----------------------------------------------------------------------------------

TauServoFrontEnd::TauServoFrontEnd(const TauModel& model) : model_(model), data_(model) {}

void TauServoFrontEnd::reset() noexcept {
  has_previous_ = false;
  qd_.setZero();
  data_.pose = model_.homePose();
}

Fault TauServoFrontEnd::update(const Vec6& q, const SurfaceContact& contact, const Vec6* pose) noexcept {
  if (!q.allFinite()) return Fault::kNonFiniteInput;
  if (contact.active && (!contact.point.allFinite() || !contact.normal.allFinite() ||
                         std::abs(contact.normal.norm() - 1.0) > 1e-6))
    return Fault::kNonFiniteInput;
  qd_ = has_previous_ ? ((q - q_) / model_.servoPeriod()).eval() : Vec6::Zero().eval();
  q_ = q;
  has_previous_ = true;
  if (pose) {
    if (!pose->allFinite()) return Fault::kNonFiniteInput;
    data_.pose = *pose;
  }
  // With a caller-supplied pose Newton starts at the solution and only evaluates J (0 iterations).
  const Fault f = model_.forward(q, data_);
  if (f != Fault::kNone) return f;
  model_.computeGravity(q, data_);
  return Fault::kNone;
}

// --- LQR wall -----------------------------------------------------------------------------------

LqrWallRenderer::LqrWallRenderer(const TauModel& model, const LqrWallGains& gains, const Options& options)
    : front_(model), regulator_(gains), options_(options) {
  if (!(options.release_distance >= 0.0)) throw Error("LqrWallRenderer: release_distance must be >= 0");
  if (!gains.Kc.allFinite() || !gains.Ki.allFinite()) throw Error("LqrWallRenderer: gains are not finite");
}

void LqrWallRenderer::reset() noexcept {
  front_.reset();
  cmd_ = WallCommand{};
  observer_started_ = false;
}

const WallCommand& LqrWallRenderer::fail(Fault f) noexcept {
  cmd_.torque.setZero();
  cmd_.fault = f;
  cmd_.in_contact = false;
  cmd_.saturated = false;
  cmd_.penetration = 0.0;
  regulator_.clearIntegral();
  regulator_.applied(cmd_.torque);
  return cmd_;
}

const WallCommand& LqrWallRenderer::tick(const Vec6& q, const SurfaceContact& contact, const Vec6* pose,
                                         const Vec6* applied) noexcept {
  const Fault f = front_.update(q, contact, pose);
  if (f != Fault::kNone) return fail(f);
  const TauData& data = front_.data();
  // The observer runs in free space too, so the velocity estimate is settled at contact entry.
  // On the first tick the observer starts at rest, as if held (the torque reported for the period
  // before it, often zero at power-up, did not act on the state it starts from).
  const bool first = !observer_started_;
  if (first) {
    regulator_.reset(q);
    observer_started_ = true;
  }
  regulator_.observe(q, first ? nullptr : applied);
  cmd_.fault = Fault::kNone;
  cmd_.saturated = false;
  if (options_.gravity_compensation) cmd_.torque = data.gravity;
  else cmd_.torque.setZero();

  const double distance = contact.active ? front_.signedDistance(contact) : 0.0;
  const bool was_in_contact = cmd_.in_contact;
  if (!contact.active || distance > options_.release_distance) cmd_.in_contact = false;
  else if (!was_in_contact && distance <= 0.0) cmd_.in_contact = true;
  cmd_.penetration = cmd_.in_contact ? std::max(0.0, -distance) : 0.0;
  if (!cmd_.in_contact) {  // free space: no IK, no LQR
    regulator_.clearIntegral();
    scaleIntoBox(cmd_.torque, front_.model().torqueLimit());
    regulator_.applied(cmd_.torque);
    return cmd_;
  }

  // Reference: the tool's own pose moved onto the surface along the normal. It follows the tool
  // tangentially (the tool slides) and keeps its orientation, so only the normal motion is held.
  const Vec3& n = contact.normal;
  if (!was_in_contact) entry_orientation_ = data.pose.tail<3>();
  if (options_.follow_tangentially || !was_in_contact) {
    // Reference: the tool position moved onto the surface along the normal (it follows the tool
    // tangentially, so the tool slides), with the orientation held from the contact entry.
    ref_pose_.head<3>() = data.pose.head<3>() - distance * n;
    ref_pose_.tail<3>() = entry_orientation_;
    const Fault ik = front_.model().inverse(ref_pose_, reference_);
    if (ik != Fault::kNone) return fail(ik);
  }
  j_lu_.compute(data.J);
  if (!(j_lu_.rcond() > 1e-9)) return fail(Fault::kSingular);
  error_.head<6>() = regulator_.velocity();
  if (options_.follow_tangentially) {
    // No velocity error along the surface either: remove the tangential tool velocity.
    const Vec6 xdot = data.J * regulator_.velocity();
    Vec6 tangential = Vec6::Zero();
    tangential.head<3>() = xdot.head<3>() - n.dot(xdot.head<3>()) * n;
    error_.head<6>() -= j_lu_.solve(tangential);
  }
  error_.tail<6>() = front_.q() - reference_;

  // Bumpless entry: x_i such that the contact torque starts at zero.
  if (!was_in_contact) regulator_.startBumpless(error_);
  Vec6 contact_torque = regulator_.control(error_);
  if (options_.follow_tangentially) {
    // A frictionless surface: drop the tangential part of the contact force (the gain couples the
    // joints, so a normal correction would otherwise also push the tool sideways).
    Vec6 wrench = j_lu_.transpose().solve(contact_torque);
    wrench.head<3>() = n.dot(wrench.head<3>()) * n;
    contact_torque.noalias() = data.J.transpose() * wrench;
  }
  if (options_.unilateral) {
    // A wall only pushes: when the contact wrench would pull the tool into the surface while the
    // tool is outside it, the user is leaving: release instead of attracting.
    const Vec6 wrench = j_lu_.transpose().solve(contact_torque);  // J^T F = tau  ->  F = J^-T tau
    if (was_in_contact && distance > 0.0 && n.dot(wrench.head<3>()) < 0.0) {
      cmd_.in_contact = false;
      cmd_.penetration = 0.0;
      regulator_.clearIntegral();
      scaleIntoBox(cmd_.torque, front_.model().torqueLimit());
      regulator_.applied(cmd_.torque);
      return cmd_;
    }
  }
  const Vec6& limit = front_.model().torqueLimit();
  if (options_.keep_direction) {
    // The largest share s <= 1 of the contact torque with |gravity_i + s contact_i| <= limit_i.
    double share = 1.0;
    for (int i = 0; i < 6; ++i) {
      const double room = contact_torque(i) > 0.0 ? limit(i) - cmd_.torque(i) : limit(i) + cmd_.torque(i);
      if (std::abs(contact_torque(i)) > room) share = std::min(share, std::max(0.0, room) / std::abs(contact_torque(i)));
    }
    cmd_.torque += share * contact_torque;
    cmd_.saturated = share < 1.0;
    clampSymmetric(cmd_.torque, limit);  // gravity compensation alone beyond a limit (not at rest)
  } else {
    cmd_.torque += contact_torque;
    // Per-joint saturation (what the motors do): the unsaturated joints keep holding at full gain.
    cmd_.saturated = clampSymmetric(cmd_.torque, limit) > 0;
  }
  // Anti-windup by conditional integration: the integrator holds while the actuators saturate.
  if (!cmd_.saturated) regulator_.integrate(error_.tail<6>());
  if (zeroIfNonFinite(cmd_.torque) != Fault::kNone) return fail(Fault::kNonFiniteResult);
  regulator_.applied(cmd_.torque);
  return cmd_;
}

// --- spring wall --------------------------------------------------------------------------------

SpringWallRenderer::SpringWallRenderer(const TauModel& model, const Options& options) : front_(model), options_(options) {
  if (!(options.stiffness >= 0.0) || !(options.damping >= 0.0) || !std::isfinite(options.stiffness + options.damping))
    throw Error("SpringWallRenderer: stiffness and damping must be finite and >= 0");
}

void SpringWallRenderer::reset() noexcept {
  front_.reset();
  cmd_ = WallCommand{};
}

const WallCommand& SpringWallRenderer::tick(const Vec6& q, const SurfaceContact& contact, const Vec6* pose) noexcept {
  const Fault f = front_.update(q, contact, pose);
  if (f != Fault::kNone) {
    cmd_ = WallCommand{};
    cmd_.fault = f;
    return cmd_;
  }
  const TauData& data = front_.data();
  cmd_.fault = Fault::kNone;
  if (options_.gravity_compensation) cmd_.torque = data.gravity;
  else cmd_.torque.setZero();
  const double distance = contact.active ? front_.signedDistance(contact) : 1.0;
  cmd_.in_contact = distance < 0.0;
  cmd_.penetration = cmd_.in_contact ? -distance : 0.0;
  if (cmd_.in_contact) {
    const Vec3& n = contact.normal;
    const double normal_speed = n.dot(data.J.topRows<3>() * front_.qd());
    // Push only: the damper may not pull the tool into the wall.
    const double force = std::max(0.0, options_.stiffness * cmd_.penetration - options_.damping * normal_speed);
    cmd_.torque.noalias() += data.J.topRows<3>().transpose() * (force * n);
  }
  cmd_.saturated = scaleIntoBox(cmd_.torque, front_.model().torqueLimit()) < 1.0;
  if (zeroIfNonFinite(cmd_.torque) != Fault::kNone) {
    cmd_ = WallCommand{};
    cmd_.fault = Fault::kNonFiniteResult;
  }
  return cmd_;
}

}  // namespace uhaptics
