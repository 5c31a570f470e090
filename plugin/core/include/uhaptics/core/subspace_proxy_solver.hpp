#pragma once
// The nonlinear subspace proxy (paper 000, eq. 6): q* = argmin_q |x_p - f(q)|^2, solved at servo
// rate by an iterative least-squares method warm-started from the previous tick's q*.
//
// Stopping rule, in task units so that joints of mixed units (m, rad) need no scaling: Gauss-Newton
// stops when an undamped correction moves the probe by less than `tolerance`, |J dq| < tolerance
// (|J dq| is the part of the residual the joints can still remove); Levenberg-Marquardt, whose
// damped steps are short anywhere, stops on |J^T r| / |J|_F < tolerance. Near a zero-residual
// optimum GN converges quadratically, so the remaining error is then far below the tolerance. Every linear solve uses the core's damped least squares (finite and bounded
// at singular configurations).
//
// Gauss-Newton is the default: on the exoskeleton it needs fewer model evaluations than
// Levenberg-Marquardt for the same accuracy (docs/exo-finger.md, "Speed"); LM is kept for models
// whose residual is large at the optimum or whose warm start is poor.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "uhaptics/core/fault.hpp"
#include "uhaptics/core/kinematic_model.hpp"
#include "uhaptics/core/model_capabilities.hpp"
#include "uhaptics/core/regularized_solve.hpp"
#include "uhaptics/core/types.hpp"

namespace uhaptics {

enum class LeastSquaresMethod : std::uint8_t { kGaussNewton, kLevenbergMarquardt };

struct SubspaceSolveOptions {
  double tolerance = 1e-10;  // stop when |J dq| < tolerance (task units, e.g. rad)
  int max_iterations = 20;   // hard cap per tick (servo budget)
  LeastSquaresMethod method = LeastSquaresMethod::kGaussNewton;
  RegularizationOptions regularization{};
  double lm_initial_damping = 1e-3;  // LM: mu, relative to diag(J^T J) (Marquardt scaling)
};

struct SubspaceSolveReport {
  int iterations = 0;        // linear solves performed
  int evaluations = 0;       // forward-kinematics evaluations (the dominant cost)
  double residual = std::numeric_limits<double>::quiet_NaN();  // |x_p - f(q*)| at the returned q*
  double last_step = std::numeric_limits<double>::quiet_NaN();  // |J dq| of the last correction
  bool converged = false;
  Fault fault = Fault::kNone;  // kNonFiniteInput / kNonFiniteResult / kNotConverged
};

/// Refines q (in: warm start, out: q*) towards argmin |x_p - f(q)|^2. Allocation-free, never throws.
/// On kNonFiniteInput / kNonFiniteResult q is left at the warm start. kNotConverged leaves the best
/// iterate found (a usable, finite q*) so the caller decides whether to use it.
template <class Model>
SubspaceSolveReport solveSubspaceProxy(const Model& model, const Vec<Model::kTask>& x_p, Vec<Model::kJoints>& q,
                                       const SubspaceSolveOptions& opt = {}) noexcept {
  static_assert(kIsKinematicModel<Model>, "solveSubspaceProxy needs a KinematicModel");
  constexpr int T = Model::kTask;
  constexpr int N = Model::kJoints;
  SubspaceSolveReport rep;
  if (!x_p.allFinite() || !q.allFinite()) {
    rep.fault = Fault::kNonFiniteInput;
    return rep;
  }
  const Vec<N> q_start = q;
  Vec<T> x;
  Mat<T, N> J;
  model.forward(q, x);
  ++rep.evaluations;
  Vec<T> r = x_p - x;
  double cost = r.squaredNorm();

  if (opt.method == LeastSquaresMethod::kGaussNewton) {
    while (rep.iterations < opt.max_iterations) {
      // x = f(q) here (the start, or the accepted step's evaluation): a model that can reuse it does.
      if constexpr (kHasJacobianFromForward<Model>) {
        model.jacobian(q, x, J);
      } else {
        model.jacobian(q, J);
      }
      RegularizedSolveInfo info;
      const Vec<N> dq = regularizedSolve(J, r, opt.regularization, &info);
      ++rep.iterations;
      rep.last_step = (J * dq).norm();
      // A damped step (ill-conditioned J) can be short without the point being optimal: only an
      // undamped short step proves stationarity (|J dq| = |projection of r on range J|).
      const bool exact_step = !info.damped();
      if (exact_step && rep.last_step < opt.tolerance) {
        // Already stationary: take the (tiny) step and stop.
        q += dq;
        model.forward(q, x);
        ++rep.evaluations;
        r = x_p - x;
        rep.converged = q.allFinite() && r.allFinite();
        break;
      }
      // Backtracking (step halving) keeps a full Gauss-Newton step from leaving the region where
      // f is defined (e.g. a linkage that cannot assemble) or from increasing the residual on a
      // far start; near the solution the full step is always accepted (quadratic convergence).
      double alpha = 1.0;
      bool accepted = false;
      for (int halvings = 0; halvings < 20 && !accepted; ++halvings, alpha *= 0.5) {
        const Vec<N> q_try = q + alpha * dq;
        model.forward(q_try, x);
        ++rep.evaluations;
        const Vec<T> r_try = x_p - x;
        if (r_try.allFinite() && r_try.squaredNorm() < cost) {
          q = q_try;
          r = r_try;
          cost = r.squaredNorm();
          accepted = true;
        }
      }
      if (!accepted) break;  // no descent along the Gauss-Newton direction: not converged
    }
    cost = r.squaredNorm();
  } else {
    // Levenberg-Marquardt with Marquardt's diagonal scaling (unit-independent) and Nielsen's
    // damping update. The damped step solves [J; sqrt(mu) D] dq = [r; 0] by the same solver.
    Mat<T + N, N> A;
    Vec<T + N> b = Vec<T + N>::Zero();
    model.jacobian(q, J);
    double mu = -1.0;
    double nu = 2.0;
    while (rep.iterations < opt.max_iterations) {
      Vec<N> d = (J.transpose() * J).diagonal().cwiseSqrt();
      const double dmax = d.maxCoeff();
      if (!(dmax > 0.0)) break;
      d = d.cwiseMax(1e-12 * dmax);
      if (mu < 0.0) mu = opt.lm_initial_damping;
      A.template topRows<T>() = J;
      A.template bottomRows<N>() = (std::sqrt(mu) * d).asDiagonal();
      b.template head<T>() = r;
      const Vec<N> dq = regularizedSolve(A, b, opt.regularization);
      ++rep.iterations;
      const Vec<T> predicted = J * dq;
      const Vec<N> q_try = q + dq;
      Vec<T> x_try;
      model.forward(q_try, x_try);
      ++rep.evaluations;
      const Vec<T> r_try = x_p - x_try;
      const double cost_try = r_try.allFinite() ? r_try.squaredNorm() : std::numeric_limits<double>::infinity();
      const double predicted_gain = cost - (r - predicted).squaredNorm();
      const double rho = predicted_gain > 0.0 ? (cost - cost_try) / predicted_gain : -1.0;
      rep.last_step = predicted.norm();
      if (rho > 0.0) {
        q = q_try;
        r = r_try;
        cost = cost_try;
        const double t = 2.0 * rho - 1.0;
        mu *= std::max(1.0 / 3.0, 1.0 - t * t * t);
        nu = 2.0;
        model.jacobian(q, J);
      } else {
        mu *= nu;
        nu *= 2.0;
      }
      // Stationarity in task units: |J^T r| / |J|_F (the part of r the joints can still reduce).
      // The damped step length is no test here: heavy damping makes it short anywhere.
      const double jnorm = J.norm();
      if (jnorm > 0.0 && (J.transpose() * r).norm() < opt.tolerance * jnorm) {
        rep.converged = true;
        break;
      }
      if (mu > 1e12) break;  // no descent at any damping: give up (reported as not converged)
    }
  }

  if (!q.allFinite() || !std::isfinite(cost)) {
    q = q_start;
    rep.converged = false;
    rep.fault = Fault::kNonFiniteResult;
    return rep;
  }
  rep.residual = std::sqrt(cost);
  if (!rep.converged) rep.fault = Fault::kNotConverged;
  return rep;
}

}  // namespace uhaptics
