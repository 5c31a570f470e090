// symmetricEigen() per size; the SVDs are in decompositions_svd_*.cpp, split so that a parallel
// build compiles them side by side.
#include "uhaptics/core/decompositions.hpp"

namespace uhaptics {
namespace {

template <typename Matrix, typename Vector>
bool solveSymmetric(const Matrix& A, Vector& values, Matrix* vectors) {
  if (!A.allFinite()) return false;
  const Eigen::SelfAdjointEigenSolver<Matrix> eig(A, vectors ? Eigen::ComputeEigenvectors : Eigen::EigenvaluesOnly);
  if (eig.info() != Eigen::Success) return false;
  values = eig.eigenvalues();
  if (vectors) *vectors = eig.eigenvectors();
  return true;
}

}  // namespace

bool symmetricEigen(const Mat2& A, Vec2& values, Mat2* vectors) noexcept { return solveSymmetric(A, values, vectors); }
bool symmetricEigen(const Mat3& A, Vec3& values, Mat3* vectors) noexcept { return solveSymmetric(A, values, vectors); }
bool symmetricEigen(const Mat6& A, Vec6& values, Mat6* vectors) noexcept { return solveSymmetric(A, values, vectors); }
bool symmetricEigen(const MatX& A, VecX& values, MatX* vectors) { return solveSymmetric(A, values, vectors); }

}  // namespace uhaptics
