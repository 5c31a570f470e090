#pragma once
// Eigenvalues of general (non-symmetric) real matrices, for set-up code and checks: the DARE's
// Hautus tests and closed-loop checks, the LQR design's pole report, and the tests that verify them.
//
// They are computed in one translation unit (eigenvalues.cpp) on purpose: Eigen's
// EigenSolver<MatrixXd> is one of the slowest instantiations to compile (docs/building.md,
// "Keeping the build fast"), and the callers only need the numbers.
#include <Eigen/Core>

#include "uhaptics/core/types.hpp"

namespace uhaptics {

/// The eigenvalues of the square matrix A (Eigen's real Schur based EigenSolver). Returns false,
/// leaving `values` unspecified, when the QR iteration does not converge or A is not square.
bool generalEigenvalues(const MatX& A, Eigen::VectorXcd& values);

/// The eigenvalues and (unit-norm) eigenvectors of A, as above.
bool generalEigenvectors(const MatX& A, Eigen::VectorXcd& values, Eigen::MatrixXcd& vectors);

/// max |eig(A)|; NaN when the eigenvalues cannot be computed, so that a check "radius < 1" fails.
double spectralRadius(const MatX& A);

}  // namespace uhaptics
