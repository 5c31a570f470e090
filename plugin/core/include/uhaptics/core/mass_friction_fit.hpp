#pragma once
// Least-squares identification of a one-axis mass with viscous and Coulomb friction from measured
// motion and force (paper 003, eq. 22, extended by a Coulomb term):
//
//   F_ext = m a + b v + f_c sign(v)
//
// Samples with |v| below a dead band are left out: near zero velocity Coulomb friction is
// indeterminate (stiction holds any force up to f_c). Offline analysis code: it allocates, never
// throws, and reports an ill-posed fit instead of returning numbers that mean nothing.
#include <Eigen/QR>
#include <cmath>
#include <vector>

#include "uhaptics/core/types.hpp"

namespace uhaptics {

struct MotionForceSample {
  double acceleration;  // [m/s^2]
  double velocity;      // [m/s]
  double force;         // external force along the axis [N]
};

struct MassFrictionFit {
  double mass = 0.0;     // m [kg]
  double viscous = 0.0;  // b [N s/m]
  double coulomb = 0.0;  // f_c [N]
  double rms = 0.0;      // residual [N]
  std::size_t samples = 0;
  // Conditioning of the column-normalized regressor (ratio of the extreme diagonal entries of its
  // pivoted QR factor): large means the excitation does not separate the terms.
  double condition = 0.0;
  bool valid = false;    // enough samples and a full-rank regressor
};

/// Fits m, b, f_c to every sample with |v| >= velocity_deadband. with_coulomb = false fits the
/// paper's two-term model (f_c = 0).
inline MassFrictionFit fitMassFriction(const std::vector<MotionForceSample>& data, double velocity_deadband,
                                       bool with_coulomb = true) {
  MassFrictionFit fit;
  const int cols = with_coulomb ? 3 : 2;
  std::vector<const MotionForceSample*> used;
  for (const auto& s : data)
    if (std::isfinite(s.acceleration) && std::isfinite(s.velocity) && std::isfinite(s.force) &&
        std::abs(s.velocity) >= velocity_deadband)
      used.push_back(&s);
  fit.samples = used.size();
  if (used.size() < static_cast<std::size_t>(2 * cols)) return fit;
  MatX A(static_cast<Eigen::Index>(used.size()), cols);
  VecX y(static_cast<Eigen::Index>(used.size()));
  for (Eigen::Index r = 0; r < A.rows(); ++r) {
    const MotionForceSample& s = *used[static_cast<std::size_t>(r)];
    A(r, 0) = s.acceleration;
    A(r, 1) = s.velocity;
    if (with_coulomb) A(r, 2) = s.velocity > 0.0 ? 1.0 : -1.0;
    y(r) = s.force;
  }
  // Column scaling makes the rank decision and the condition number unit-independent.
  const VecX scale = A.colwise().norm().transpose();
  if (!(scale.minCoeff() > 0.0)) return fit;
  const MatX As = A * scale.cwiseInverse().asDiagonal();
  const Eigen::ColPivHouseholderQR<MatX> qr(As);
  if (qr.rank() < cols) return fit;
  const VecX theta = scale.cwiseInverse().asDiagonal() * qr.solve(y);
  const auto R = qr.matrixR().topLeftCorner(cols, cols).diagonal().cwiseAbs();
  fit.condition = R.maxCoeff() / R.minCoeff();
  fit.mass = theta(0);
  fit.viscous = theta(1);
  fit.coulomb = with_coulomb ? theta(2) : 0.0;
  fit.rms = std::sqrt((A * theta - y).squaredNorm() / static_cast<double>(A.rows()));
  fit.valid = theta.allFinite();
  return fit;
}

}  // namespace uhaptics
