#include "uhaptics/core/dare.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/QR>
#include <cmath>
#include <complex>
#include <sstream>

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
  Eigen::EigenSolver<MatX> eig(A, false);
  if (eig.info() != Eigen::Success) {
    if (why) *why = "eigenvalues of A could not be computed";
    return false;
  }
  const double scale = std::max(1.0, A.stableNorm());
  MatC stacked(n + X.cols(), n);
  for (Eigen::Index k = 0; k < n; ++k) {
    const Complex lambda = eig.eigenvalues()(k);
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

void requireFinite(const MatX& M, const char* name) {
  if (!M.allFinite()) throw Error(std::string("DARE: ") + name + " contains NaN or Inf");
}

}  // namespace

bool isStabilizable(const MatX& A, const MatX& B, double rank_tolerance, std::string* why) {
  return hautus(A, normalizedColumns(B), rank_tolerance, "not controllable from B", why);
}

bool isDetectable(const MatX& A, const MatX& Q, double rank_tolerance, std::string* why) {
  // Q = C^T C: rows of C from the eigen-decomposition of Q, dropping its null space.
  Eigen::SelfAdjointEigenSolver<MatX> es(0.5 * (Q + Q.transpose()));
  const double q_max = std::max(es.eigenvalues().cwiseAbs().maxCoeff(), 0.0);
  const double cut = 1e-14 * static_cast<double>(Q.rows()) * q_max;
  MatX Ct(Q.rows(), 0);
  for (Eigen::Index i = 0; i < Q.rows(); ++i) {
    if (es.eigenvalues()(i) > cut) {
      Ct.conservativeResize(Eigen::NoChange, Ct.cols() + 1);
      Ct.col(Ct.cols() - 1) = es.eigenvectors().col(i);  // unit norm already
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
  if (Eigen::SelfAdjointEigenSolver<MatX>(Q, Eigen::EigenvaluesOnly).eigenvalues().minCoeff() < -1e-12 * q_scale)
    throw Error("DARE: Q is not positive semidefinite");

  if (options.check_preconditions) {
    std::string why;
    if (!isStabilizable(A, B, options.rank_tolerance, &why))
      throw Error("DARE: (A, B) is not stabilizable: " + why + "; no stabilizing LQR gain exists");
    if (!isDetectable(A, Q, options.rank_tolerance, &why))
      throw Error("DARE: (A, Q) is not detectable: " + why + "; penalize that mode in Q");
  }

  // SDA iteration: A_k -> 0, G_k -> controllability Gramian-like term, H_k -> P.
  const MatX BLinvT = r_llt.matrixL().solve(B.transpose()).transpose();  // B L^-T
  MatX Ak = A;
  MatX Gk = BLinvT * BLinvT.transpose();  // B R^-1 B^T
  MatX Hk = Q;
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
    const double change = (Hnext - Hk).stableNorm();
    Hk = std::move(Hnext);
    result.iterations = k + 1;
    if (!Hk.allFinite()) break;
    if (change <= options.tolerance * Hk.stableNorm()) {
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
  result.P = std::move(Hk);
  const MatX BtP = B.transpose() * result.P;
  result.K = (R + BtP * B).ldlt().solve(BtP * A);

  // Own verification: residual, symmetry/PSD of P, and a stabilizing closed loop.
  result.relative_residual = dareRelativeResidual(A, B, Q, R, result.P);
  if (!(result.relative_residual <= options.max_relative_residual)) {
    std::ostringstream s;
    s << "DARE: solution failed its residual check (relative residual " << result.relative_residual << " > "
      << options.max_relative_residual << ")";
    throw Error(s.str());
  }
  const double p_min =
      Eigen::SelfAdjointEigenSolver<MatX>(result.P, Eigen::EigenvaluesOnly).eigenvalues().minCoeff();
  if (p_min < -1e-9 * std::max(result.P.stableNorm(), 1.0))
    throw Error("DARE: solution is not positive semidefinite (the pair is not stabilizable or not detectable)");
  const MatX closed = A - B * result.K;
  result.closed_loop_spectral_radius = Eigen::EigenSolver<MatX>(closed, false).eigenvalues().cwiseAbs().maxCoeff();
  if (!(result.closed_loop_spectral_radius < 1.0)) {
    std::ostringstream s;
    s << "DARE: the gain does not stabilize the plant (spectral radius " << result.closed_loop_spectral_radius
      << "); (A, B) is not stabilizable or (A, Q) not detectable";
    throw Error(s.str());
  }
  return result;
}

}  // namespace uhaptics
