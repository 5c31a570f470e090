#pragma once
// Force manipulability ellipsoid (FME) shaping for kinematically redundant devices (paper 003):
//
//   M_hat = (J W W J^T)^-1,  W = diag(1 / T_i)           torque-limit-weighted FME (eq. 9)
//   nu(M_hat, M_des) = logdet((M_hat + M_des) / 2) - 1/2 logdet(M_hat M_des)   (eq. 10)
//
// nu is the Jensen-Bregman log-det divergence: zero iff M_hat = M_des, positive otherwise. Its
// differential is d nu = tr(G dM_hat) with G = (M_hat + M_des)^-1 - M_hat^-1 / 2, and
// dM_hat/dq_k = -M_hat (dJ_k W W J^T + J W W dJ_k^T) M_hat, so with H = M_hat G M_hat (symmetric)
//   d nu / d q_k = -2 <H J W W, dJ_k>_F,
// one Frobenius product per joint once H J W W is formed. Everything here is fixed-size and
// allocation-free; functions report failure instead of throwing so that servo code can call them.
#include <Eigen/Cholesky>
#include <cmath>
#include <limits>

#include "uhaptics/core/decompositions.hpp"
#include "uhaptics/core/types.hpp"

namespace uhaptics::fme {

/// W W = diag(1 / T_i^2) from the torque limits T_i (> 0).
template <int N>
Vec<N> inverseSquaredLimits(const Vec<N>& torque_limits) noexcept {
  return torque_limits.array().square().inverse().matrix();
}

/// Velocity-side ellipsoid A = J W W J^T (the inverse of the FME).
template <int M, int N>
Mat<M, M> weightedVelocityEllipsoid(const Mat<M, N>& J, const Vec<N>& inv_limits_sq) noexcept {
  return J * inv_limits_sq.asDiagonal() * J.transpose();
}

/// M_hat = (J W W J^T)^-1. Returns false (Mhat untouched) when J W W J^T is singular to within
/// min_inverse_condition = lambda_min / lambda_max of J W W J^T (a singular arm has no finite FME).
template <int M, int N>
bool weightedFme(const Mat<M, N>& J, const Vec<N>& inv_limits_sq, Mat<M, M>& Mhat,
                 double min_inverse_condition = 1e-8) noexcept {
  const Mat<M, M> A = weightedVelocityEllipsoid(J, inv_limits_sq);
  if (!A.allFinite()) return false;
  Vec<M> lambda;  // ascending
  Mat<M, M> V;
  if (!symmetricEigen(A, lambda, &V)) return false;
  if (!(lambda(M - 1) > 0.0) || !(lambda(0) > min_inverse_condition * lambda(M - 1))) return false;
  Mhat = V * lambda.cwiseInverse().asDiagonal() * V.transpose();
  return true;
}

/// log det of a symmetric positive definite matrix; false when it is not positive definite.
template <int M>
bool logDetSpd(const Mat<M, M>& S, double& logdet) noexcept {
  Eigen::LLT<Mat<M, M>> llt(S);
  if (llt.info() != Eigen::Success) return false;
  const auto d = llt.matrixLLT().diagonal();
  if (!(d.minCoeff() > 0.0)) return false;
  logdet = 2.0 * d.array().log().sum();
  return std::isfinite(logdet);
}

/// True when S is symmetric (to 1e-9 relative) and positive definite.
template <int M>
bool isSymmetricPositiveDefinite(const Mat<M, M>& S) noexcept {
  if (!S.allFinite()) return false;
  const double scale = S.cwiseAbs().maxCoeff();
  if (!(scale > 0.0) || (S - S.transpose()).cwiseAbs().maxCoeff() > 1e-9 * scale) return false;
  double unused = 0.0;
  return logDetSpd(S, unused);
}

/// nu(X, Y) for SPD X (the FME) and Y (the desired FME). If G is given it receives
/// (X + Y)^-1 - X^-1 / 2, the matrix whose trace against dX is d nu. Returns false (nu = NaN)
/// when X, Y or X + Y is not positive definite.
template <int M>
bool logDetDivergence(const Mat<M, M>& X, const Mat<M, M>& Y, double& nu, Mat<M, M>* G = nullptr) noexcept {
  nu = std::numeric_limits<double>::quiet_NaN();
  double ld_x = 0.0, ld_y = 0.0, ld_sum = 0.0;
  const Mat<M, M> S = X + Y;
  if (!logDetSpd(X, ld_x) || !logDetSpd(Y, ld_y) || !logDetSpd(S, ld_sum)) return false;
  nu = ld_sum - M * std::log(2.0) - 0.5 * (ld_x + ld_y);
  if (G) {
    Eigen::LLT<Mat<M, M>> llt_s(S), llt_x(X);
    *G = llt_s.solve(Mat<M, M>::Identity()) - 0.5 * llt_x.solve(Mat<M, M>::Identity());
  }
  return true;
}

/// d nu / d q from G (see logDetDivergence), the FME X = M_hat, J, W W and the Jacobian
/// derivatives dJ[k] = dJ / dq_k.
template <int M, int N, typename DerivativeArray>
void divergenceGradient(const Mat<M, M>& G, const Mat<M, M>& X, const Mat<M, N>& J, const Vec<N>& inv_limits_sq,
                        const DerivativeArray& dJ, Vec<N>& grad) noexcept {
  const Mat<M, M> H = X * G * X;
  const Mat<M, N> P = H * J * inv_limits_sq.asDiagonal();
  for (int k = 0; k < N; ++k) grad(k) = -2.0 * P.cwiseProduct(dJ[k]).sum();
}

/// Desired FME with one principal axis along direction u (any length) of length `along` and all
/// others of length `across` (eq. 11-13 in closed form: U diag(.) U^T = along u u^T + across (I - u u^T)).
/// Free motion: along = zeta (minor axis on the motion). Stiff contact: along = K (major axis on the force).
/// Returns false (Mdes untouched) when u is zero or non-finite or the lengths are not positive.
template <int M>
bool axisAlignedEllipsoid(const Vec<M>& u, double along, double across, Mat<M, M>& Mdes) noexcept {
  const double norm = u.norm();
  if (!(norm > 0.0) || !std::isfinite(norm) || !(along > 0.0) || !(across > 0.0) || !std::isfinite(along) ||
      !std::isfinite(across))
    return false;
  const Vec<M> n = u / norm;
  const Mat<M, M> P = n * n.transpose();
  Mdes = along * P + across * (Mat<M, M>::Identity() - P);
  return true;
}

/// The paper's axis lengths: K = mu lambda_max(M_hat_0), zeta = lambda_min(M_hat_0) / mu.
struct EllipsoidScales {
  double major = 0.0;  // K
  double minor = 0.0;  // zeta
};
template <int M>
EllipsoidScales ellipsoidScales(const Mat<M, M>& Mhat_home, double mu) noexcept {
  Vec<M> lambda;  // ascending
  if (!symmetricEigen(Mhat_home, lambda)) lambda.setConstant(std::numeric_limits<double>::quiet_NaN());
  return {mu * lambda(M - 1), lambda(0) / mu};
}

/// Largest force magnitude the joints can exert along direction u without any |tau_i| > T_i:
/// f_max = min_i T_i / |(J^T u)_i| (u normalized). Infinity when J^T u = 0.
template <int M, int N>
double maxForceAlong(const Mat<M, N>& J, const Vec<N>& torque_limits, const Vec<M>& u) noexcept {
  const Vec<N> tau_per_newton = J.transpose() * u.normalized();
  double f = std::numeric_limits<double>::infinity();
  for (int i = 0; i < N; ++i) {
    const double a = std::abs(tau_per_newton(i));
    if (a > 0.0) f = std::min(f, torque_limits(i) / a);
  }
  return f;
}

}  // namespace uhaptics::fme
