#pragma once
// Damped least squares with a singular-value-dependent damping (Maciejewski & Klein 1988).
//
//   minimize |r - A x|^2 + lambda^2 |x|^2,  x = sum_i s_i / (s_i^2 + lambda^2) (u_i^T r) v_i
//
// lambda is zero while the smallest singular value s_min stays above epsilon * s_max, so a
// well-conditioned A gets the exact least-squares (minimum-norm) answer; below that threshold
// lambda^2 = (1 - (s_min / (epsilon s_max))^2) (lambda_max s_max)^2 grows smoothly, which bounds
// |x| <= |r| / (2 lambda) and keeps the output continuous through a singularity. Both thresholds
// are relative to s_max so that matrices with mixed units (m vs rad) are treated alike.
#include <cmath>
#include <limits>

#include "uhaptics/core/decompositions.hpp"  // the fixed-size SVDs, compiled once
#include "uhaptics/core/types.hpp"

namespace uhaptics {

struct RegularizationOptions {
  double epsilon = 1e-3;     // damping starts when s_min / s_max drops below this
  double lambda_max = 1e-2;  // damping at an exact singularity, relative to s_max
};

struct RegularizedSolveInfo {
  double sigma_max = 0.0;
  double sigma_min = 0.0;
  double lambda = 0.0;  // damping actually used (absolute)
  bool damped() const noexcept { return lambda > 0.0; }
  double inverseCondition() const noexcept { return sigma_max > 0.0 ? sigma_min / sigma_max : 0.0; }
};

/// Damping for given singular values; exposed so callers can reason about the regularizer.
inline double dampingFor(double sigma_max, double sigma_min, const RegularizationOptions& opt) noexcept {
  const double threshold = opt.epsilon * sigma_max;
  if (!(sigma_min < threshold) || threshold <= 0.0) return 0.0;
  const double ratio = sigma_min / threshold;
  return std::sqrt(1.0 - ratio * ratio) * opt.lambda_max * sigma_max;
}

/// Solves min |r - A x|^2 (+ damping near singularities). Fixed-size A allocates nothing.
/// A zero matrix yields x = 0. Non-finite input yields x = 0 and sigma_max = NaN in info.
template <typename MatA, typename VecR>
Eigen::Matrix<double, MatA::ColsAtCompileTime, 1> regularizedSolve(
    const Eigen::MatrixBase<MatA>& A, const Eigen::MatrixBase<VecR>& r,
    const RegularizationOptions& opt = {}, RegularizedSolveInfo* info = nullptr) {
  using Result = Eigen::Matrix<double, MatA::ColsAtCompileTime, 1>;
  using Plain = Eigen::Matrix<double, MatA::RowsAtCompileTime, MatA::ColsAtCompileTime>;
  Result x = Result::Zero(A.cols());
  if (!A.allFinite() || !r.allFinite()) {
    if (info) *info = {std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0};
    return x;
  }
  Eigen::JacobiSVD<Plain> svd(A, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const auto& s = svd.singularValues();
  const double s_max = s.size() ? s(0) : 0.0;
  // Rank-deficient shapes (more unknowns than equations) have implicit zero singular values in
  // the directions A cannot see; the minimum-norm solution leaves those at zero.
  const double s_min = s.size() ? s(s.size() - 1) : 0.0;
  const double lambda = dampingFor(s_max, s_min, opt);
  if (s_max > 0.0) {
    const auto utr = (svd.matrixU().leftCols(s.size()).transpose() * r).eval();
    for (Eigen::Index i = 0; i < s.size(); ++i) {
      const double denom = s(i) * s(i) + lambda * lambda;
      if (denom > 0.0 && s(i) > 0.0) x += (s(i) / denom * utr(i)) * svd.matrixV().col(i);
    }
  }
  if (info) *info = {s_max, s_min, lambda};
  return x;
}

}  // namespace uhaptics
