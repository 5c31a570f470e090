#pragma once
// Central finite differences, used to check analytic derivatives and for numerical linearization.
#include <Eigen/Core>
#include <algorithm>
#include <cmath>

namespace uhaptics {

/// Step that balances truncation and round-off error for central differences: h ~ eps^(1/3) |x|.
inline double centralDifferenceStep(double x, double rel = 6.0e-6) noexcept {
  return rel * std::max(1.0, std::abs(x));
}

/// J(i, j) = d f_i / d x_j by central differences. f maps an Eigen vector to an Eigen vector.
/// Fixed sizes stay on the stack; h <= 0 picks centralDifferenceStep per coordinate.
template <typename F, typename Derived>
auto centralDifferenceJacobian(F&& f, const Eigen::MatrixBase<Derived>& x0, double h = 0.0) {
  using X = typename Derived::PlainObject;
  X x = x0;
  const auto y0 = f(x);
  using Y = std::decay_t<decltype(y0)>;
  Eigen::Matrix<double, Y::RowsAtCompileTime, X::RowsAtCompileTime> J(y0.size(), x.size());
  for (Eigen::Index j = 0; j < x.size(); ++j) {
    const double step = h > 0.0 ? h : centralDifferenceStep(x0(j));
    x(j) = x0(j) + step;
    const Y yp = f(x);
    x(j) = x0(j) - step;
    const Y ym = f(x);
    x(j) = x0(j);
    J.col(j) = (yp - ym) / (2.0 * step);
  }
  return J;
}

}  // namespace uhaptics
