#pragma once
// Rendering through an underactuated device (Lobo et al., World Haptics 2017, paper 000).
//
// A device state q = (q_a, q_n) has actuated joints q_a = S q and sensed-only joints q_n; the probe
// x = f(q) lives in the virtual (task) space, J = df/dq = (J_a, J_n). Given the proxy x_p found by
// the environment and the deviation dx = x_p - f(q), the three forms of the paper are
//
//   standard (eq. 1):             tau_a = J_a^T Z_x dx
//   null-space force opt. (eq. 4): tau_a = J_a^T P_n Z_x dx,   P_n = I - J_n (J_n^T J_n)^-1 J_n^T
//   linearized subspace (eq. 8):  tau_a = Z_q S dq,            dq = argmin |dx - J dq|^2
//
// and their displayed impedances d tau / d q with tau = S^T tau_a (proxy held still, J held
// constant, the paper's two approximations): eq. 2, eq. 5 and eq. 9.
//
// Every inverse goes through the core's damped least squares (regularized_solve.hpp): exact while
// s_min / s_max >= epsilon (default 1e-3), smoothly damped below that, so commands stay finite and
// bounded at singular configurations. Everything is fixed-size and allocation-free.
//
// The nonlinear subspace proxy (eq. 6) is in subspace_proxy_solver.hpp.
#include <cmath>
#include <limits>

#include "uhaptics/core/decompositions.hpp"
#include "uhaptics/core/fault.hpp"
#include "uhaptics/core/regularized_pseudo_inverse.hpp"
#include "uhaptics/core/regularized_solve.hpp"
#include "uhaptics/core/types.hpp"

namespace uhaptics::underactuated {

/// True when S is a selection matrix: each row a distinct unit row of the identity.
template <int A, int N>
bool isSelection(const Mat<A, N>& S) noexcept {
  for (int i = 0; i < A; ++i) {
    int ones = 0, col = -1;
    for (int j = 0; j < N; ++j) {
      if (S(i, j) == 1.0) { ++ones; col = j; }
      else if (S(i, j) != 0.0) return false;
    }
    if (ones != 1) return false;
    for (int k = 0; k < i; ++k)
      if (S(k, col) == 1.0) return false;
  }
  return true;
}

/// The selection of the non-actuated joints: q_n = S_n q, rows in increasing joint order.
/// Precondition: isSelection(S).
template <int A, int N>
Mat<N - A, N> complementSelection(const Mat<A, N>& S) noexcept {
  Mat<N - A, N> Sn = Mat<N - A, N>::Zero();
  int row = 0;
  for (int j = 0; j < N && row < N - A; ++j) {
    if (S.col(j).isZero()) Sn(row++, j) = 1.0;
  }
  return Sn;
}

/// P_n = I - J_n J_n^+: removes the part of a task force that would load the non-actuated joints
/// (eq. 3-4). J_n^+ is the damped pseudo-inverse, so P_n stays bounded when J_n loses rank (then
/// it tends to I in the lost direction: no force is removed where J_n cannot see it).
template <int T, int N, int A>
Mat<T, T> nullSpaceProjector(const Mat<T, N>& J, const Mat<N - A, N>& Sn, const RegularizationOptions& reg = {},
                             RegularizedSolveInfo* info = nullptr) {
  Mat<T, T> P = Mat<T, T>::Identity();
  if constexpr (N > A) {
    const Mat<T, N - A> Jn = J * Sn.transpose();
    P.noalias() -= Jn * regularizedPseudoInverse(Jn, reg, info);
  } else if (info) {
    *info = {};
  }
  return P;
}

/// Standard proxy rendering projected onto the actuators (eq. 1): tau_a = S J^T Z_x dx.
template <int T, int N, int A>
Vec<A> standardForce(const Mat<T, N>& J, const Mat<A, N>& S, const Mat<T, T>& Zx, const Vec<T>& dx) noexcept {
  return S * (J.transpose() * (Zx * dx));
}

/// Null-space force optimization (eq. 4): tau_a = S J^T P_n Z_x dx.
template <int T, int N, int A>
Vec<A> nullSpaceForce(const Mat<T, N>& J, const Mat<A, N>& S, const Mat<T, T>& P_n, const Mat<T, T>& Zx,
                      const Vec<T>& dx) noexcept {
  return S * (J.transpose() * (P_n * (Zx * dx)));
}

/// Linearized subspace step (eq. 7): dq = argmin |dx - J dq|^2 by the damped least squares.
template <int T, int N>
Vec<N> linearizedSubspaceStep(const Mat<T, N>& J, const Vec<T>& dx, const RegularizationOptions& reg = {},
                              RegularizedSolveInfo* info = nullptr) {
  return regularizedSolve(J, dx, reg, info);
}

/// Subspace force from a joint-space deviation (eq. 6 and 8): tau_a = Z_q S dq.
template <int N, int A>
Vec<A> subspaceForce(const Mat<A, N>& S, const Mat<A, A>& Zq, const Vec<N>& dq) noexcept {
  return Zq * (S * dq);
}

/// Displayed impedance of the standard method (eq. 2): d tau / d q = -S^T J_a^T Z_x J.
template <int T, int N, int A>
Mat<N, N> standardImpedance(const Mat<T, N>& J, const Mat<A, N>& S, const Mat<T, T>& Zx) noexcept {
  return -(S.transpose() * S) * J.transpose() * Zx * J;
}

/// Displayed impedance of null-space force optimization (eq. 5): -S^T J_a^T P_n Z_x J.
template <int T, int N, int A>
Mat<N, N> nullSpaceImpedance(const Mat<T, N>& J, const Mat<A, N>& S, const Mat<T, T>& P_n,
                             const Mat<T, T>& Zx) noexcept {
  return -(S.transpose() * S) * J.transpose() * P_n * Zx * J;
}

/// Displayed impedance of the subspace methods (eq. 9): -S^T Z_q S, independent of the
/// configuration. (For the linearized method this holds while J has full column rank and is not
/// damped; with damping it becomes -S^T Z_q S J^+_lambda J, see linearizedSubspaceImpedance.)
template <int N, int A>
Mat<N, N> subspaceImpedance(const Mat<A, N>& S, const Mat<A, A>& Zq) noexcept {
  return -S.transpose() * Zq * S;
}

/// What the linearized method really displays under the paper's approximations, regularizer
/// included: -S^T Z_q S J^+_lambda J (equals eq. 9 wherever J has full column rank and no damping).
template <int T, int N, int A>
Mat<N, N> linearizedSubspaceImpedance(const Mat<T, N>& J, const Mat<A, N>& S, const Mat<A, A>& Zq,
                                      const RegularizationOptions& reg = {}) {
  return -S.transpose() * Zq * S * (regularizedPseudoInverse(J, reg) * J);
}

/// The actuated block d tau_a / d q_a of a full displayed impedance (what Fig. 4 plots).
template <int N, int A>
Mat<A, A> actuatedBlock(const Mat<N, N>& K, const Mat<A, N>& S) noexcept {
  return S * K * S.transpose();
}

/// Displayed stiffness measured between two frames, along the actuated motion:
///   k = (d tau_a . d q_a) / |d q_a|^2   (= d tau_a / d q_a for one actuator).
/// Passive when k <= 0 (the device absorbs energy along the motion). Returns NaN when
/// |d q_a| <= min_step: a frame without actuated motion says nothing about the impedance.
template <int A>
double finiteDifferenceStiffness(const Vec<A>& dtau_a, const Vec<A>& dq_a, double min_step) noexcept {
  const double n2 = dq_a.squaredNorm();
  if (!(n2 > min_step * min_step) || !dtau_a.allFinite()) return std::numeric_limits<double>::quiet_NaN();
  return dtau_a.dot(dq_a) / n2;
}

/// Passivity of a theoretical displayed impedance: the symmetric part of its actuated block is
/// negative semi-definite up to tol (for one actuator: d tau_a / d q_a <= tol).
template <int N, int A>
bool isPassive(const Mat<N, N>& K, const Mat<A, N>& S, double tol = 0.0) noexcept {
  const Mat<A, A> Ka = actuatedBlock(K, S);
  if constexpr (A == 1) {
    return Ka(0, 0) <= tol;
  } else {
    const Mat<A, A> sym = 0.5 * (Ka + Ka.transpose());
    // Gershgorin is conservative; the sizes here are tiny, so use the exact largest eigenvalue.
    Vec<A> lambda;
    return symmetricEigen(sym, lambda) && lambda.maxCoeff() <= tol;
  }
}

}  // namespace uhaptics::underactuated
