#pragma once
// The heavy fixed-size decompositions, compiled once (decompositions*.cpp) instead of in every file
// that uses them: Eigen's SelfAdjointEigenSolver and JacobiSVD are among the slowest templates to
// instantiate (docs/building.md, "Keeping the build fast").
//
// - symmetricEigen(): the eigen-decomposition of a symmetric matrix, one compiled overload per size
//   the project uses (2, 3, 6 and dynamic); other fixed sizes fall back to Eigen's solver inline.
// - JacobiSVD of the project's fixed sizes (2x2, 2x3, 3x2, 2x4, 4x2, 6x6): declared extern here and
//   instantiated once, so `Eigen::JacobiSVD<Mat<2, 4>>` anywhere after this header costs a call.
//   Include this header before the first use of such an SVD in a file.
#include <Eigen/Eigenvalues>
#include <Eigen/SVD>

#include "uhaptics/core/types.hpp"

namespace uhaptics {

/// The eigenvalues of the symmetric matrix A, ascending, and with `vectors` its orthonormal
/// eigenvectors as columns in the same order (Eigen's SelfAdjointEigenSolver; only the lower
/// triangle of A is read). Returns false, the outputs unspecified, when A is not finite or the
/// iteration does not converge. Fixed sizes allocate nothing.
bool symmetricEigen(const Mat2& A, Vec2& values, Mat2* vectors = nullptr) noexcept;
bool symmetricEigen(const Mat3& A, Vec3& values, Mat3* vectors = nullptr) noexcept;
bool symmetricEigen(const Mat6& A, Vec6& values, Mat6* vectors = nullptr) noexcept;
bool symmetricEigen(const MatX& A, VecX& values, MatX* vectors = nullptr);

/// Other fixed sizes: the same, instantiated where used.
template <int N>
bool symmetricEigen(const Mat<N, N>& A, Vec<N>& values, Mat<N, N>* vectors = nullptr) noexcept {
  if (!A.allFinite()) return false;
  const Eigen::SelfAdjointEigenSolver<Mat<N, N>> eig(A, vectors ? Eigen::ComputeEigenvectors : Eigen::EigenvaluesOnly);
  if (eig.info() != Eigen::Success) return false;
  values = eig.eigenvalues();
  if (vectors) *vectors = eig.eigenvectors();
  return true;
}

}  // namespace uhaptics

extern template class Eigen::JacobiSVD<uhaptics::Mat<2, 2>>;
extern template class Eigen::JacobiSVD<uhaptics::Mat<2, 3>>;
extern template class Eigen::JacobiSVD<uhaptics::Mat<3, 2>>;
extern template class Eigen::JacobiSVD<uhaptics::Mat<2, 4>>;
extern template class Eigen::JacobiSVD<uhaptics::Mat<4, 2>>;
extern template class Eigen::JacobiSVD<uhaptics::Mat<6, 6>>;
