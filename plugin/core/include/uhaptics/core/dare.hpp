#pragma once
// Discrete-time algebraic Riccati equation (DARE) for LQR design:
//
//   P = A^T P A - A^T P B (R + B^T P B)^-1 B^T P A + Q,   K = (R + B^T P B)^-1 B^T P A.
//
// Algorithm: the structure-preserving doubling algorithm (SDA, Chu, Fan, Lin & Wang 2004), the
// choice of WPILib's wpimath. SciPy (solve_discrete_are) and SLICOT (SB02OD) instead order the
// generalized Schur form (QZ) of the symplectic pencil, optionally after balancing; Drake's
// DiscreteAlgebraicRiccatiEquation is also Schur based. We chose SDA because (i) it needs only
// n x n LU solves and products (no QZ, which Eigen lacks for reordering), (ii) it converges
// quadratically, so the paper's hard weights (1e7 on integrators whose discrete eigenvalues sit at
// exactly 1, next to fast velocity modes) take a few doublings where the plain Riccati recursion
// needs hundreds of steps, and (iii) it is cheap enough to redesign within the 1 ms servo period
// (figures: docs/tau.md, "DARE solver"). Because SDA's preconditions are not checked by the
// iteration itself, we check them explicitly (Hautus/PBH tests on the eigenvalues outside the open
// unit disc), verify the residual and the closed loop afterwards, and throw uhaptics::Error rather
// than return a wrong P.
// All of this runs in balanced state units: a power-of-two diagonal scaling that minimizes the norms
// of A (off-diagonal), B R^-1 B^T and Q together, so the rank tests, the stopping rule and the
// checks give the same verdict whatever units the caller's states are in (a rank test in raw units
// refuses an integrator coupled to the input through a 1e-8 static gain as "not stabilizable").
#include <string>

#include "uhaptics/core/types.hpp"

namespace uhaptics {

struct DareOptions {
  int max_iterations = 100;
  double tolerance = 1e-13;          // stops SDA: max |dP_ij| / sqrt(P_ii P_jj) between doublings
  double max_relative_residual = 1e-8;  // accepted |residual|_F / (|Q|_F + |A^T P A|_F), balanced units
  double rank_tolerance = 1e-10;     // PBH rank test: sigma_min < tol * scale means rank loss
  bool check_preconditions = true;   // stabilizability of (A, B), detectability of (A, Q)
};

struct DareResult {
  MatX P;                      // stabilizing solution, symmetric positive semidefinite
  MatX K;                      // optimal gain (R + B^T P B)^-1 B^T P A
  int iterations = 0;          // doublings used
  double relative_residual = 0.0;  // in the balanced state units (see above)
  double closed_loop_spectral_radius = 0.0;  // max |eig(A - B K)| (< 1 for a stabilizing P)
};

/// Solves the DARE; throws uhaptics::Error with a message naming the cause when the input is
/// malformed (sizes, non-finite, R not positive definite, Q not symmetric PSD), when (A, B) is not
/// stabilizable or (A, Q) not detectable, or when the solution fails its own residual check.
DareResult solveDare(const MatX& A, const MatX& B, const MatX& Q, const MatX& R, const DareOptions& options = {});

/// |P - (A^T P A - A^T P B (R + B^T P B)^-1 B^T P A + Q)|_F / (|Q|_F + |A^T P A|_F).
double dareRelativeResidual(const MatX& A, const MatX& B, const MatX& Q, const MatX& R, const MatX& P);

/// The Hautus tests, in the units given (solveDare calls them on its balanced A, B, Q). B's columns
/// and Q's diagonal are normalized first (input and output units do not matter). On failure `why`
/// says which eigenvalue is uncontrollable/unobservable.
bool isStabilizable(const MatX& A, const MatX& B, double rank_tolerance = 1e-10, std::string* why = nullptr);
bool isDetectable(const MatX& A, const MatX& Q, double rank_tolerance = 1e-10, std::string* why = nullptr);

}  // namespace uhaptics
