#include "uhaptics/core/dare.hpp"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <Eigen/QR>
#include <cmath>
#include <complex>
#include <limits>
#include <sstream>

#include "uhaptics/core/decompositions.hpp"
#include "uhaptics/core/eigenvalues.hpp"
#include "uhaptics/core/fault.hpp"

namespace uhaptics {
namespace {

using Complex = std::complex<double>;
using MatC = Eigen::MatrixXcd;

std::string describe(const Complex& lambda) {
  std::ostringstream s;
  s.precision(6);
  s << lambda.real();
  if (lambda.imag() != 0.0) s << (lambda.imag() > 0 ? "+" : "-") << std::abs(lambda.imag()) << "i";
  s << " (|z| = " << std::abs(lambda) << ")";
  return s.str();
}

// Columns scaled to unit norm: column scaling of B (rows of C) changes neither controllability
// nor observability, and it keeps a weight of 1 next to a weight of 1e7 from looking like rank loss.
MatX normalizedColumns(const MatX& M) {
  MatX out = M;
  for (Eigen::Index j = 0; j < out.cols(); ++j) {
    const double n = out.col(j).stableNorm();
    if (n > 0.0) out.col(j) /= n;
  }
  return out;
}

// Hautus test: rank [A - lambda I, X] == n for every eigenvalue lambda of A with |lambda| >= 1.
// X is given with unit-norm columns, so the threshold is relative to max(1, |A|).
bool hautus(const MatX& A, const MatX& X, double rank_tolerance, const char* what, std::string* why) {
  const Eigen::Index n = A.rows();
  Eigen::VectorXcd eigenvalues;
  if (!generalEigenvalues(A, eigenvalues)) {
    if (why) *why = "eigenvalues of A could not be computed";
    return false;
  }
  const double scale = std::max(1.0, A.stableNorm());
  MatC stacked(n + X.cols(), n);
  for (Eigen::Index k = 0; k < n; ++k) {
    const Complex lambda = eigenvalues(k);
    // Marginal modes (|z| = 1: integrators, rigid-body modes) must be checked too; allow for the
    // rounding of a computed eigenvalue.
    if (std::abs(lambda) < 1.0 - 1e-9) continue;
    // [A - lambda I, X] has full row rank  <=>  its conjugate transpose has full column rank.
    stacked.topRows(n) = (A.cast<Complex>() - lambda * MatC::Identity(n, n)).adjoint();
    stacked.bottomRows(X.cols()) = X.transpose().cast<Complex>();
    Eigen::ColPivHouseholderQR<MatC> qr(stacked);
    const double r_min = std::abs(qr.matrixQR()(n - 1, n - 1));
    if (r_min < rank_tolerance * scale) {
      if (why) {
        std::ostringstream s;
        s << "eigenvalue " << describe(lambda) << " of A is on or outside the unit circle and is " << what
          << " (Hautus test: smallest pivot " << r_min << " < " << rank_tolerance * scale << ")";
        *why = s.str();
      }
      return false;
    }
  }
  return true;
}

// Scale of every state for the precondition tests: x = D x_b with D = diag(2^k), chosen by
// coordinate descent to minimize |offdiag(D^-1 A D)|^2 + |D^-1 G D^-1|^2 + |D Q D|^2, G = B R^-1 B^T
// (the blocks of the DARE's symplectic pencil, which SLICOT and SciPy balance before their solves).
// Why this and not A alone: a rank test judges "zero" relative to the other entries, so its verdict
// depends on the state units. The objective is convex in log d, and a diagonal similarity of the
// plant (A -> S A S^-1, B -> S B, Q -> S^-1 Q S^-1) only shifts log d, so the balanced triple, and
// with it the verdict, is the same in any state units up to the power-of-2 rounding. G rather than
// B makes it independent of input units, and a common factor on Q and R shifts all log d equally.
// Q matters: an integrator that feeds nothing back (an empty column of A) has its scale set only by
// its weight; balancing A alone would leave it in the caller's units, where a weak but real input
// coupling (paper 001's integrators next to fast joint modes) looks like rank loss.
// A state with entries on one side only (e.g. decoupled and unweighted) has no minimum and keeps d = 1.
VecX balancingScale(const MatX& A, const MatX& G, const MatX& Q) {
  const Eigen::Index n = A.rows();
  MatX Ab = A, Gb = G, Qb = Q;
  VecX d = VecX::Ones(n);
  for (int sweep = 0; sweep < 100; ++sweep) {
    bool changed = false;
    for (Eigen::Index i = 0; i < n; ++i) {
      // f(s) = left1 / s^2 + left2 / s^4 + right1 s^2 + right2 s^4 when d_i is multiplied by s.
      double left1 = Gb.row(i).squaredNorm() + Gb.col(i).squaredNorm() - 2.0 * Gb(i, i) * Gb(i, i);
      double right1 = Qb.row(i).squaredNorm() + Qb.col(i).squaredNorm() - 2.0 * Qb(i, i) * Qb(i, i);
      left1 += Ab.row(i).squaredNorm() - Ab(i, i) * Ab(i, i);
      right1 += Ab.col(i).squaredNorm() - Ab(i, i) * Ab(i, i);
      const double left2 = Gb(i, i) * Gb(i, i), right2 = Qb(i, i) * Qb(i, i);
      const double left = left1 + left2, right = right1 + right2;
      if (!(left > 0.0) || !(right > 0.0) || !std::isfinite(left + right)) continue;
      const auto f = [&](int k) {
        const double s2 = std::ldexp(1.0, 2 * k), s4 = std::ldexp(1.0, 4 * k);
        return left1 / s2 + left2 / s4 + right1 * s2 + right2 * s4;
      };
      // f is convex in k: walk downhill in whole powers of two (exact, no rounding).
      int k = 0;
      const int step = f(1) < f(0) ? 1 : (f(-1) < f(0) ? -1 : 0);
      if (step == 0) continue;
      while (std::abs(k) < 200 && f(k + step) < f(k)) k += step;
      if (!(f(k) < 0.95 * f(0))) continue;  // a margin so that the sweeps terminate
      const double s = std::ldexp(1.0, k);
      d(i) *= s;
      Ab.row(i) /= s;
      Ab.col(i) *= s;
      Gb.row(i) /= s;
      Gb.col(i) /= s;
      Qb.row(i) *= s;
      Qb.col(i) *= s;
      changed = true;
    }
    if (!changed) break;
  }
  return d;
}

void requireFinite(const MatX& M, const char* name) {
  if (!M.allFinite()) throw Error(std::string("DARE: ") + name + " contains NaN or Inf");
}

}  // namespace

bool isStabilizable(const MatX& A, const MatX& B, double rank_tolerance, std::string* why) {
  return hautus(A, normalizedColumns(B), rank_tolerance, "not controllable from B", why);
}

bool isDetectable(const MatX& A, const MatX& Q, double rank_tolerance, std::string* why) {
  // Q = C^T C. Output scaling (rows of C) changes no observability, so Q is first brought to unit
  // diagonal, Q = W Qn W with W = sqrt(diag Q): a weight of 1e-80 next to 1 is then a full output
  // (as B's columns are normalized above), while a null direction of a non-diagonal Q still shows as
  // an eigenvalue of Qn at rounding level. States with zero weight keep W = 0.
  const Eigen::Index n = Q.rows();
  const MatX Qs = 0.5 * (Q + Q.transpose());
  VecX w(n), w_inv(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    w(i) = Qs(i, i) > 0.0 ? std::sqrt(Qs(i, i)) : 0.0;
    w_inv(i) = w(i) > 0.0 ? 1.0 / w(i) : 0.0;
  }
  // Rows of C from the eigen-decomposition of Qn, dropping its null space.
  VecX q_eigen;
  MatX q_vectors;
  if (!symmetricEigen(MatX(w_inv.asDiagonal() * Qs * w_inv.asDiagonal()), q_eigen, &q_vectors))
    throw Error("DARE: Q's eigenvalues cannot be computed");
  const double q_max = std::max(q_eigen.cwiseAbs().maxCoeff(), 0.0);
  const double cut = 1e-14 * static_cast<double>(n) * q_max;
  MatX Ct(n, 0);
  for (Eigen::Index i = 0; i < n; ++i) {
    if (q_eigen(i) > cut) {
      const VecX c = w.asDiagonal() * q_vectors.col(i);
      Ct.conservativeResize(Eigen::NoChange, Ct.cols() + 1);
      Ct.col(Ct.cols() - 1) = c / c.stableNorm();
    }
  }
  // Observability of (A, C) is controllability of (A^T, C^T).
  return hautus(A.transpose(), Ct, rank_tolerance, "not observable through Q", why);
}

double dareRelativeResidual(const MatX& A, const MatX& B, const MatX& Q, const MatX& R, const MatX& P) {
  const MatX AtPA = A.transpose() * P * A;
  const MatX BtPA = B.transpose() * P * A;
  const MatX S = R + B.transpose() * P * B;
  const MatX rhs = AtPA - BtPA.transpose() * S.ldlt().solve(BtPA) + Q;
  return (P - rhs).stableNorm() / std::max(Q.stableNorm() + AtPA.stableNorm(), 1e-300);
}

DareResult solveDare(const MatX& A, const MatX& B, const MatX& Q, const MatX& R, const DareOptions& options) {
  const Eigen::Index n = A.rows(), m = B.cols();
  if (A.cols() != n || B.rows() != n || Q.rows() != n || Q.cols() != n || R.rows() != m || R.cols() != m || m == 0) {
    std::ostringstream s;
    s << "DARE: inconsistent sizes A " << A.rows() << "x" << A.cols() << ", B " << B.rows() << "x" << B.cols()
      << ", Q " << Q.rows() << "x" << Q.cols() << ", R " << R.rows() << "x" << R.cols();
    throw Error(s.str());
  }
  requireFinite(A, "A");
  requireFinite(B, "B");
  requireFinite(Q, "Q");
  requireFinite(R, "R");
  const double q_scale = std::max(Q.stableNorm(), 1e-300);
  if ((Q - Q.transpose()).stableNorm() > 1e-12 * q_scale) throw Error("DARE: Q is not symmetric");
  if ((R - R.transpose()).stableNorm() > 1e-12 * std::max(R.stableNorm(), 1e-300)) throw Error("DARE: R is not symmetric");
  Eigen::LLT<MatX> r_llt(R);
  if (r_llt.info() != Eigen::Success) throw Error("DARE: R is not positive definite");
  VecX q_eigen;
  if (!symmetricEigen(Q, q_eigen)) throw Error("DARE: Q is not finite");
  if (q_eigen.minCoeff() < -1e-12 * q_scale) throw Error("DARE: Q is not positive semidefinite");

  // Everything below runs in balanced state units (balancingScale): x = D x_b, so A_b = D^-1 A D,
  // B_b = D^-1 B, Q_b = D Q D, P = D^-1 P_b D^-1, K = K_b D^-1. D holds powers of two, so the change
  // of units is exact; it makes the rank tests' thresholds and the doubling's rounding independent of
  // the caller's state units (eigenvalues and ranks are unchanged by the similarity).
  const MatX BLinvT = r_llt.matrixL().solve(B.transpose()).transpose();  // B L^-T
  const VecX d = balancingScale(A, BLinvT * BLinvT.transpose(), Q);
  const VecX d_inv = d.cwiseInverse();
  const MatX Ab = d_inv.asDiagonal() * A * d.asDiagonal();
  const MatX Bb = d_inv.asDiagonal() * B;
  const MatX Qb = d.asDiagonal() * Q * d.asDiagonal();
  if (options.check_preconditions) {
    std::string why;
    if (!isStabilizable(Ab, Bb, options.rank_tolerance, &why))
      throw Error("DARE: (A, B) is not stabilizable: " + why + "; no stabilizing LQR gain exists");
    if (!isDetectable(Ab, Qb, options.rank_tolerance, &why))
      throw Error("DARE: (A, Q) is not detectable: " + why + "; penalize that mode in Q");
  }

  // SDA iteration: A_k -> 0, G_k -> controllability Gramian-like term, H_k -> P.
  MatX Ak = Ab;
  MatX Gk = d_inv.asDiagonal() * BLinvT * BLinvT.transpose() * d_inv.asDiagonal();  // B_b R^-1 B_b^T
  MatX Hk = Qb;
  const MatX I = MatX::Identity(n, n);
  DareResult result;
  bool converged = false;
  Eigen::PartialPivLU<MatX> lu(n);
  for (int k = 0; k < options.max_iterations; ++k) {
    lu.compute(I + Gk * Hk);
    const MatX V1 = lu.solve(Ak);
    const MatX V2 = lu.solve(Gk);
    const MatX Gnext = Gk + Ak * V2 * Ak.transpose();
    MatX Hnext = Hk + V1.transpose() * Hk * Ak;
    Ak = Ak * V1;
    Gk = 0.5 * (Gnext + Gnext.transpose());
    Hnext = 0.5 * (Hnext + Hnext.transpose());
    // Change of every entry relative to sqrt(H_ii H_jj) (its bound for a PSD H): a state with a
    // small weight next to heavy ones converges on its own scale, not on the heaviest state's.
    // (Square roots taken separately: P reaches 1e163 for the weakest inputs, where H_ii H_jj overflows.)
    const VecX root = Hnext.diagonal().cwiseAbs().cwiseSqrt();
    double change = 0.0;
    for (Eigen::Index j = 0; j < n; ++j)
      for (Eigen::Index i = 0; i < n; ++i) {
        const double delta = std::abs(Hnext(i, j) - Hk(i, j));
        if (delta > 0.0) change = std::max(change, delta / root(i) / root(j));
      }
    Hk = std::move(Hnext);
    result.iterations = k + 1;
    if (!Hk.allFinite()) break;
    if (change <= options.tolerance) {
      converged = true;
      break;
    }
  }
  if (!Hk.allFinite())
    throw Error("DARE: the doubling iteration diverged (non-finite P); the problem is not stabilizable/detectable "
                "or badly scaled");
  if (!converged) {
    std::ostringstream s;
    s << "DARE: the doubling iteration did not converge in " << options.max_iterations
      << " iterations (closed loop marginally stable: check stabilizability and detectability)";
    throw Error(s.str());
  }
  const MatX& Pb = Hk;
  const MatX BtP = Bb.transpose() * Pb;
  const MatX Kb = (R + BtP * Bb).ldlt().solve(BtP * Ab);

  // Own verification (in balanced units): residual, symmetry/PSD of P, and a stabilizing closed loop.
  result.relative_residual = dareRelativeResidual(Ab, Bb, Qb, R, Pb);
  if (!(result.relative_residual <= options.max_relative_residual)) {
    std::ostringstream s;
    s << "DARE: solution failed its residual check (relative residual " << result.relative_residual << " > "
      << options.max_relative_residual << ")";
    throw Error(s.str());
  }
  VecX p_eigen;
  const double p_min = symmetricEigen(Pb, p_eigen) ? p_eigen.minCoeff() : std::numeric_limits<double>::quiet_NaN();
  if (p_min < -1e-9 * std::max(Pb.stableNorm(), 1.0))
    throw Error("DARE: solution is not positive semidefinite (the pair is not stabilizable or not detectable)");
  const MatX closed = Ab - Bb * Kb;
  result.closed_loop_spectral_radius = spectralRadius(closed);
  if (!(result.closed_loop_spectral_radius < 1.0)) {
    std::ostringstream s;
    s << "DARE: the gain does not stabilize the plant (spectral radius " << result.closed_loop_spectral_radius
      << "); (A, B) is not stabilizable or (A, Q) not detectable";
    throw Error(s.str());
  }
  result.P = d_inv.asDiagonal() * Pb * d_inv.asDiagonal();
  result.K = Kb * d_inv.asDiagonal();
  return result;
}

}  // namespace uhaptics
