#pragma once
// Configuration optimization along the self-motion manifold: with the end effector held at
// x_target, move the joints in the null space of J to minimize the FME-matching cost nu
// (what the null-space controller does over time, done here as an offline descent for the paper's
// static studies: the 3-DoF example and the workspace map). Not servo code: set-up/analysis only.
#include <algorithm>
#include <cmath>

#include "uhaptics/core/fme_cost.hpp"
#include "uhaptics/core/joint_limits.hpp"
#include "uhaptics/core/regularized_solve.hpp"

namespace uhaptics::fme {

struct SelfMotionOptions {
  int max_iterations = 4000;
  double initial_step = 1e-3;      // rad per unit gradient, adapted by backtracking
  double max_joint_step = 0.05;    // rad, largest joint change per iteration
  double gradient_tolerance = 1e-7;  // on the null-space-projected gradient
  double position_tolerance = 1e-9;  // m
  // With joint limits: minimize nu + limit_weight P(q) (joint_limits.hpp), the potential the
  // null-space controller descends when limit_weight = limit_gain / beta.
  double limit_weight = 0.0;
  double limit_margin = 0.25;  // rad
};

struct SelfMotionResult {
  int iterations = 0;
  double nu = 0.0;
  double projected_gradient_norm = 0.0;
  double position_error = 0.0;
  double limit_potential = 0.0;  // P(q) at the end (0 when no limit is within its margin)
  bool converged = false;
  bool valid = false;  // false when the cost was undefined along the way (singular arm)
};

/// Newton steps (damped near singularities) that move q until forward(q) = x_target; returns the
/// remaining position error [m]. Also a plain inverse kinematics from a starting guess.
template <class Model>
double projectOnto(const Model& model, Vec<Model::kJoints>& q, const Vec<Model::kTask>& x_target) {
  Vec<Model::kTask> x;
  Mat<Model::kTask, Model::kJoints> J;
  double err = 0.0;
  for (int i = 0; i < 20; ++i) {
    model.forward(q, x);
    const Vec<Model::kTask> dx = x_target - x;
    err = dx.norm();
    if (err < 1e-13) break;
    model.jacobian(q, J);
    q += regularizedSolve(J, dx);
  }
  return err;
}

/// Moves q (in place) to a local minimum of nu(q) (+ limit_weight P(q) when `limits` is given)
/// subject to forward(q) = x_target.
template <class Model>
SelfMotionResult optimizeSelfMotion(const Model& model, Vec<Model::kJoints>& q, const Vec<Model::kTask>& x_target,
                                    const Vec<Model::kJoints>& inv_limits_sq,
                                    const Mat<Model::kTask, Model::kTask>& Mdes, const SelfMotionOptions& opt = {},
                                    const JointLimits<Model::kJoints>* limits = nullptr) {
  constexpr int N = Model::kJoints, M = Model::kTask;
  const bool use_limits = limits != nullptr && opt.limit_weight > 0.0;
  // Total cost; false where nu is undefined.
  auto cost = [&](const Vec<N>& qc, double& nu_out, double& total_out) {
    if (!fmeCostValue(model, qc, inv_limits_sq, Mdes, nu_out)) return false;
    total_out = nu_out + (use_limits ? opt.limit_weight * jointLimitPotential(*limits, qc, opt.limit_margin) : 0.0);
    return true;
  };
  SelfMotionResult r;
  r.position_error = projectOnto(model, q, x_target);
  Mat<M, N> J;
  Vec<N> grad, limit_grad;
  double step = opt.initial_step, total = 0.0;
  for (r.iterations = 0; r.iterations < opt.max_iterations; ++r.iterations) {
    model.jacobian(q, J);
    if (!fmeCostGradient(model, q, J, inv_limits_sq, Mdes, GradientMethod::kAnalytic, r.nu, grad)) return r;
    total = r.nu;
    if (use_limits) {
      total += opt.limit_weight * jointLimitPotential(*limits, q, opt.limit_margin);
      jointLimitGradient(*limits, q, opt.limit_margin, limit_grad);
      grad += opt.limit_weight * limit_grad;
    }
    const Vec<N> g_null = grad - regularizedSolve(J, (J * grad).eval());
    r.projected_gradient_norm = g_null.norm();
    if (r.projected_gradient_norm < opt.gradient_tolerance) {
      r.converged = true;
      break;
    }
    // Backtracking: accept the first step (capped at max_joint_step) that lowers nu.
    bool accepted = false;
    for (int tries = 0; tries < 40 && !accepted; ++tries) {
      const double scale = std::min(step, opt.max_joint_step / g_null.cwiseAbs().maxCoeff());
      Vec<N> trial = q - scale * g_null;
      projectOnto(model, trial, x_target);
      double nu_trial = 0.0, total_trial = 0.0;
      if (cost(trial, nu_trial, total_trial) && total_trial < total) {
        q = trial;
        accepted = true;
        step = std::min(step * 1.5, 1e3);
      } else {
        step *= 0.5;
      }
    }
    if (!accepted) {  // no descent at any step size: a (numerically) stationary point
      r.converged = true;
      break;
    }
  }
  r.position_error = projectOnto(model, q, x_target);
  r.valid = cost(q, r.nu, total);
  r.limit_potential = use_limits ? jointLimitPotential(*limits, q, opt.limit_margin) : 0.0;
  return r;
}

}  // namespace uhaptics::fme
