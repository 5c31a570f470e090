#pragma once
// Null-space projection for torque-controlled redundant devices (Khatib's dynamically consistent
// inverse, paper 003 eq. 3-4):
//
//   J# = M^-1 J^T (J M^-1 J^T)^-1,   tau_N = (I - J^T J#^T) tau_S.
//
// With this J#, tau_N produces no end-effector acceleration (J M^-1 tau_N = 0) and, because
// J#^T J^T = I, no end-effector force either (J#^T tau_N = 0). Passing M^-1 = I gives the kinematic
// (Moore-Penrose) projector instead.
#include <Eigen/Cholesky>

#include "uhaptics/core/types.hpp"

namespace uhaptics {

/// Fills NT = I - J^T J#^T (and Jsharp when given). Returns false (outputs untouched) when
/// J M^-1 J^T is not positive definite (J singular or M^-1 not positive definite).
template <int M, int N>
bool nullSpaceProjector(const Mat<M, N>& J, const Mat<N, N>& Minv, Mat<N, N>& NT, Mat<N, M>* Jsharp = nullptr) noexcept {
  const Mat<N, M> MinvJt = Minv * J.transpose();
  const Mat<M, M> Lambda_inv = J * MinvJt;
  Eigen::LLT<Mat<M, M>> llt(Lambda_inv);
  if (llt.info() != Eigen::Success) return false;
  const Mat<N, M> Js = MinvJt * llt.solve(Mat<M, M>::Identity());  // J#
  if (!Js.allFinite()) return false;
  NT = Mat<N, N>::Identity() - J.transpose() * Js.transpose();
  if (Jsharp) *Jsharp = Js;
  return true;
}

}  // namespace uhaptics
