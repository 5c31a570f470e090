#pragma once
// The matrix form of regularizedSolve: A^+_lambda = V diag(s / (s^2 + lambda^2)) U^T, with the same
// singular-value-dependent damping (see regularized_solve.hpp), so that
// regularizedPseudoInverse(A) * r == regularizedSolve(A, r). Used where the same pseudo-inverse is
// applied to several vectors or needed as a matrix (projectors, impedance analysis).
#include <cmath>
#include <limits>

#include "uhaptics/core/decompositions.hpp"  // the fixed-size SVDs, compiled once
#include "uhaptics/core/regularized_solve.hpp"

namespace uhaptics {

/// Damped pseudo-inverse of A (cols x rows). Fixed-size A allocates nothing. Non-finite A gives a
/// zero matrix and sigma_max = NaN in info, like regularizedSolve.
template <typename MatA>
Eigen::Matrix<double, MatA::ColsAtCompileTime, MatA::RowsAtCompileTime> regularizedPseudoInverse(
    const Eigen::MatrixBase<MatA>& A, const RegularizationOptions& opt = {}, RegularizedSolveInfo* info = nullptr) {
  using Result = Eigen::Matrix<double, MatA::ColsAtCompileTime, MatA::RowsAtCompileTime>;
  using Plain = Eigen::Matrix<double, MatA::RowsAtCompileTime, MatA::ColsAtCompileTime>;
  Result pinv = Result::Zero(A.cols(), A.rows());
  if (!A.allFinite()) {
    if (info) *info = {std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0};
    return pinv;
  }
  if constexpr (MatA::ColsAtCompileTime == 1 || MatA::RowsAtCompileTime == 1) {
    // A vector has one singular value |a| = s_max = s_min: never damped, a^+ = a^T / |a|^2.
    // (Closed form also sidesteps a GCC maybe-uninitialized false positive in JacobiSVD of vectors.)
    const double n2 = A.squaredNorm();
    if (n2 > 0.0) pinv = A.transpose() / n2;
    if (info) *info = {std::sqrt(n2), std::sqrt(n2), 0.0};
    return pinv;
  } else {
    Eigen::JacobiSVD<Plain> svd(A, Eigen::ComputeFullU | Eigen::ComputeFullV);
    const auto& s = svd.singularValues();
    const double s_max = s.size() ? s(0) : 0.0;
    const double s_min = s.size() ? s(s.size() - 1) : 0.0;
    const double lambda = dampingFor(s_max, s_min, opt);
    for (Eigen::Index i = 0; i < s.size(); ++i) {
      const double denom = s(i) * s(i) + lambda * lambda;
      if (denom > 0.0 && s(i) > 0.0)
        pinv.noalias() += (s(i) / denom) * svd.matrixV().col(i) * svd.matrixU().col(i).transpose();
    }
    if (info) *info = {s_max, s_min, lambda};
    return pinv;
  }
}

}  // namespace uhaptics
