#include "uhaptics/renderers/tau_wall_design.hpp"

#include <Eigen/LU>
#include <cmath>
#include <string>

#include "uhaptics/core/dare.hpp"
#include "uhaptics/core/lqr_design.hpp"

namespace uhaptics {

namespace {

struct ControllerDesign {
  LqrWallDesign wall;
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
  LqrWallGains& gains = out.wall.gains;
  LqrWallDesignReport& report = out.wall.report;
  report.operating_pose = operating_pose;
  report.delay = delay;
  if (model.inverse(operating_pose, report.operating_joints) != Fault::kNone)
    throw Error("designLqrWall: the operating pose is outside the reachable workspace");
  TauData data(model);
  data.pose = operating_pose;
  if (model.forward(report.operating_joints, data) != Fault::kNone)
    throw Error("designLqrWall: forward kinematics fails at the operating pose (singular configuration)");
  model.computeGravity(report.operating_joints, data);

  LqrDesignRequest req;
  req.dynamics = [&model, &data](const VecX& x, const VecX& u, VecX& xdot) {
    Vec<12> xd;
    if (model.stateDerivative(x, u, data, xd) != Fault::kNone) xd.setConstant(std::nan(""));
    xdot = xd;
  };
  req.x0 = VecX::Zero(12);
  req.x0.tail(6) = report.operating_joints;
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
  gains.Kd.leftCols(6 * command_delay) = d.Kd;
  Eigen::PartialPivLU<Mat6> lu(gains.Ki);
  if (!(lu.rcond() > 1e-12)) throw Error("designLqrWall: integral gain is singular; bumpless entry impossible");
  gains.Ki_inverse = lu.inverse();
  gains.period = req.period;
  gains.operating_torque = data.gravity;
  report.ms_spectral_radius = d.random.mean_square_spectral_radius;
  report.fastest_pole_rad_s = d.fastest_pole_rad_s;
  report.dare_residual = delay.random ? d.random.relative_residual : d.dare.relative_residual;
  report.dare_iterations = delay.random ? d.random.iterations : d.dare.iterations;
  out.discrete_A = d.discrete.A;
  out.discrete_B = d.discrete.B;
  return out;
}

}  // namespace

ObserverNoise observerNoiseForDelay(int command_delay) noexcept {
  ObserverNoise noise;
  if (command_delay > 0) noise.disturbance_process = 0.01;
  return noise;
}

LqrWallDesign designLqrWall(const TauModel& model, const Vec6& operating_pose, const LqrWallWeights& w,
                            const ObserverNoise& noise, int command_delay) {
  CommandDelayDesign delay;
  delay.samples = command_delay;
  return designLqrWall(model, operating_pose, w, noise, delay);
}

LqrWallDesign designLqrWall(const TauModel& model, const Vec6& operating_pose, const LqrWallWeights& w,
                            const ObserverNoise& noise, const CommandDelayDesign& delay) {
  ControllerDesign controller = designController(model, operating_pose, w, delay, true);
  const MatX& Ad = controller.discrete_A;
  const MatX& Bd = controller.discrete_B;

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
  JointDisturbanceObserver::Gains& observer = controller.wall.gains.observer;
  observer.joints = controller.wall.report.operating_joints;
  observer.torque = controller.wall.gains.operating_torque;
  observer.A = Ao;
  observer.B = Bo;
  observer.gain = kf.P * C.transpose() * S.inverse();
  return controller.wall;
}

LqrWallDesign redesignLqrWallGains(const TauModel& model, const Vec6& operating_pose, const LqrWallDesign& designed,
                                   const LqrWallWeights& w) {
  // The structure (stabilizability/detectability) does not change with the operating point inside
  // the singularity-free workspace; the residual and closed-loop checks still run on every solve.
  LqrWallDesign out = designController(model, operating_pose, w, designed.report.delay, false).wall;
  out.gains.observer = designed.gains.observer;
  return out;
}

}  // namespace uhaptics
