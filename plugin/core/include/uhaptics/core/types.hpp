#pragma once
// Fixed-size Eigen aliases used across uhaptics. Devices fix their dimensions at compile time, so
// servo-rate code works on stack-allocated matrices and never touches the heap.
#include <Eigen/Core>

namespace uhaptics {

template <int N>
using Vec = Eigen::Matrix<double, N, 1>;

template <int Rows, int Cols>
using Mat = Eigen::Matrix<double, Rows, Cols, (Cols == 1 && Rows != 1) ? Eigen::ColMajor
                                              : (Rows == 1 && Cols != 1) ? Eigen::RowMajor
                                                                          : Eigen::ColMajor>;

using Vec2 = Vec<2>;
using Vec3 = Vec<3>;
using Vec6 = Vec<6>;
using Mat2 = Mat<2, 2>;
using Mat3 = Mat<3, 3>;
using Mat6 = Mat<6, 6>;
using VecX = Eigen::VectorXd;
using MatX = Eigen::MatrixXd;

}  // namespace uhaptics
