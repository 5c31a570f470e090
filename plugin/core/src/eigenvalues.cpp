#include "uhaptics/core/eigenvalues.hpp"

#include <Eigen/Eigenvalues>
#include <limits>

namespace uhaptics {
namespace {
bool decompose(const MatX& A, bool with_vectors, Eigen::VectorXcd& values, Eigen::MatrixXcd* vectors) {
  if (A.rows() != A.cols()) return false;
  if (A.size() == 0) {
    values.resize(0);
    if (vectors) vectors->resize(0, 0);
    return true;
  }
  const Eigen::EigenSolver<MatX> solver(A, with_vectors);
  if (solver.info() != Eigen::Success) return false;
  values = solver.eigenvalues();
  if (vectors) *vectors = solver.eigenvectors();
  return true;
}
}  // namespace

bool generalEigenvalues(const MatX& A, Eigen::VectorXcd& values) { return decompose(A, false, values, nullptr); }

bool generalEigenvectors(const MatX& A, Eigen::VectorXcd& values, Eigen::MatrixXcd& vectors) {
  return decompose(A, true, values, &vectors);
}

double spectralRadius(const MatX& A) {
  Eigen::VectorXcd values;
  if (!A.allFinite() || !generalEigenvalues(A, values)) return std::numeric_limits<double>::quiet_NaN();
  return values.size() == 0 ? 0.0 : values.cwiseAbs().maxCoeff();
}

}  // namespace uhaptics
