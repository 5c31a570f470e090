#pragma once
// Singularity tests on an LU factorization that decide like Eigen's rcond() estimate but usually
// without running it (the estimate costs several triangular solves, and servo code such as the
// TAU's forward kinematics and LQR wall tests every factorization it uses).
//
// With P A = L U: ||A||_1 <= ||L||_1 ||U||_1 and ||A^-1||_1 <= ||U^-1||_1 ||L^-1||_1, and for a
// triangular T, |T^-1| <= C(T)^-1 elementwise, C(T) the comparison matrix (|t_ii| on the diagonal,
// -|t_ij| off it), so ||T^-1||_1 <= ||C(T)^-T 1||_inf: one triangular substitution. That gives a
// guaranteed lower bound of the true reciprocal condition number; Eigen's estimate of ||A^-1||_1 is
// a lower bound of the true norm, so its rcond() is at least the true one. A bound above twice the
// threshold (margin for rounding) therefore decides "above"; otherwise rcond() itself decides.
#include <Eigen/LU>
#include <cmath>

#include "uhaptics/core/types.hpp"

namespace uhaptics {

/// A lower bound of the reciprocal 1-norm condition number of the factorized matrix (0 when a
/// pivot is zero, NaN for non-finite factors). Allocation-free for fixed sizes.
template <typename MatrixType>
double rcondLowerBound(const Eigen::PartialPivLU<MatrixType>& lu) noexcept {
  const auto& LU = lu.matrixLU();
  const Eigen::Index n = LU.rows();
  double norm_l = 0.0, norm_u = 0.0;
  for (Eigen::Index j = 0; j < n; ++j) {
    double col_l = 1.0, col_u = 0.0;  // L has a unit diagonal
    for (Eigen::Index i = 0; i <= j; ++i) col_u += std::abs(LU(i, j));
    for (Eigen::Index i = j + 1; i < n; ++i) col_l += std::abs(LU(i, j));
    // Written so that a NaN propagates (std::max would drop it).
    if (!(col_l <= norm_l)) norm_l = col_l;
    if (!(col_u <= norm_u)) norm_u = col_u;
  }
  // C(U)^T y = 1 (lower triangular) and C(L)^T z = 1 (unit upper triangular); y, z >= 0.
  Eigen::Matrix<double, MatrixType::RowsAtCompileTime, 1, 0, MatrixType::MaxRowsAtCompileTime, 1> y(n), z(n);
  double inv_u = 0.0, inv_l = 0.0;
  for (Eigen::Index i = 0; i < n; ++i) {
    double s = 1.0;
    for (Eigen::Index j = 0; j < i; ++j) s += std::abs(LU(j, i)) * y(j);
    y(i) = s / std::abs(LU(i, i));
    if (!(y(i) <= inv_u)) inv_u = y(i);
  }
  for (Eigen::Index i = n - 1; i >= 0; --i) {
    double s = 1.0;
    for (Eigen::Index j = i + 1; j < n; ++j) s += std::abs(LU(j, i)) * z(j);
    z(i) = s;
    if (!(z(i) <= inv_l)) inv_l = z(i);
  }
  return 1.0 / (norm_l * norm_u * inv_u * inv_l);
}

/// lu.rcond() > threshold, decided by rcondLowerBound() when it can.
template <typename MatrixType>
bool rcondAbove(const Eigen::PartialPivLU<MatrixType>& lu, double threshold) noexcept {
  if (rcondLowerBound(lu) > 2.0 * threshold) return true;
  return lu.rcond() > threshold;
}

}  // namespace uhaptics
