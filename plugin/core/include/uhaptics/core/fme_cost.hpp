#pragma once
// The FME-matching cost nu(q) of paper 003 for any kinematic model, and its gradient: analytic
// (from the model's Jacobian derivatives, or from a central difference of its Jacobian when the
// model has none) or by central differences of nu itself (the reference the analytic one is checked
// and benchmarked against). Allocation-free; returns false instead of throwing.
#include <array>

#include "uhaptics/core/finite_difference.hpp"
#include "uhaptics/core/force_manipulability.hpp"
#include "uhaptics/core/model_capabilities.hpp"

namespace uhaptics::fme {

enum class GradientMethod { kAnalytic, kFiniteDifference };

/// dJ[k] = dJ/dq_k for every joint: the model's own derivatives when it has them (all at once
/// when it offers that), else central differences of jacobian().
template <class Model>
void jacobianDerivatives(const Model& model, const Vec<Model::kJoints>& q,
                         std::array<Mat<Model::kTask, Model::kJoints>, Model::kJoints>& dJ) noexcept {
  constexpr int N = Model::kJoints;
  if constexpr (kHasJacobianDerivatives<Model>) {
    model.jacobianDerivatives(q, dJ);
  } else if constexpr (kHasJacobianDerivative<Model>) {
    for (int k = 0; k < N; ++k) model.jacobianDerivative(q, k, dJ[k]);
  } else {
    Vec<N> qh = q;
    Mat<Model::kTask, N> Jp, Jm;
    for (int k = 0; k < N; ++k) {
      const double h = centralDifferenceStep(q(k));
      qh(k) = q(k) + h;
      model.jacobian(qh, Jp);
      qh(k) = q(k) - h;
      model.jacobian(qh, Jm);
      qh(k) = q(k);
      dJ[k] = (Jp - Jm) / (2.0 * h);
    }
  }
}

/// nu at q (no gradient). False when the FME or the divergence is undefined there.
template <class Model>
bool fmeCostValue(const Model& model, const Vec<Model::kJoints>& q, const Vec<Model::kJoints>& inv_limits_sq,
                  const Mat<Model::kTask, Model::kTask>& Mdes, double& nu) noexcept {
  Mat<Model::kTask, Model::kJoints> J;
  model.jacobian(q, J);
  Mat<Model::kTask, Model::kTask> Mhat;
  if (!weightedFme(J, inv_limits_sq, Mhat)) return false;
  return logDetDivergence(Mhat, Mdes, nu);
}

/// nu and d nu/dq at q, given J = jacobian(q) (the caller usually has it already). False when
/// J W W J^T is singular to within min_inverse_condition (see weightedFme) or nu is undefined.
/// fd_relative_step: the central-difference step of kFiniteDifference (centralDifferenceStep's
/// default sits at the knee of its error curve: tools/bench/rhi_bench.cpp, docs/benchmarks.md).
template <class Model>
bool fmeCostGradient(const Model& model, const Vec<Model::kJoints>& q, const Mat<Model::kTask, Model::kJoints>& J,
                     const Vec<Model::kJoints>& inv_limits_sq, const Mat<Model::kTask, Model::kTask>& Mdes,
                     GradientMethod method, double& nu, Vec<Model::kJoints>& grad,
                     double min_inverse_condition = 1e-8, double fd_relative_step = 6.0e-6) noexcept {
  constexpr int N = Model::kJoints, M = Model::kTask;
  Mat<M, M> Mhat, G;
  if (!weightedFme(J, inv_limits_sq, Mhat, min_inverse_condition) || !logDetDivergence(Mhat, Mdes, nu, &G))
    return false;
  if (method == GradientMethod::kAnalytic) {
    std::array<Mat<M, N>, N> dJ;
    jacobianDerivatives(model, q, dJ);
    divergenceGradient(G, Mhat, J, inv_limits_sq, dJ, grad);
    return grad.allFinite();
  }
  Vec<N> qh = q;
  for (int k = 0; k < N; ++k) {
    const double h = centralDifferenceStep(q(k), fd_relative_step);
    double plus = 0.0, minus = 0.0;
    qh(k) = q(k) + h;
    const bool ok_plus = fmeCostValue(model, qh, inv_limits_sq, Mdes, plus);
    qh(k) = q(k) - h;
    const bool ok_minus = fmeCostValue(model, qh, inv_limits_sq, Mdes, minus);
    qh(k) = q(k);
    if (!ok_plus || !ok_minus) return false;
    grad(k) = (plus - minus) / (2.0 * h);
  }
  return true;
}

}  // namespace uhaptics::fme
