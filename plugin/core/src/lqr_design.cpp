#include "uhaptics/core/lqr_design.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <complex>
#include <sstream>
#include <unsupported/Eigen/MatrixFunctions>

#include "uhaptics/core/fault.hpp"
#include "uhaptics/core/finite_difference.hpp"

namespace uhaptics {

StateSpace linearize(const DynamicsFunction& f, const VecX& x0, const VecX& u0) {
  if (!f) throw Error("linearize: no dynamics function given");
  if (!x0.allFinite() || !u0.allFinite()) throw Error("linearize: operating point is not finite");
  const Eigen::Index n = x0.size(), m = u0.size();
  VecX xdot(n);
  VecX u = u0;
  StateSpace ss;
  ss.A = centralDifferenceJacobian(
      [&](const VecX& x) {
        xdot.setZero();
        f(x, u0, xdot);
        return VecX(xdot);
      },
      x0);
  ss.B = centralDifferenceJacobian(
      [&](const VecX& uu) {
        xdot.setZero();
        f(x0, uu, xdot);
        return VecX(xdot);
      },
      u);
  if (ss.A.rows() != n || ss.B.cols() != m) throw Error("linearize: dynamics returned a wrongly sized xdot");
  if (!ss.A.allFinite() || !ss.B.allFinite())
    throw Error("linearize: the dynamics are not finite near the operating point (singular configuration?)");
  return ss;
}

StateSpace augmentWithIntegrators(const StateSpace& plant, const MatX& C) {
  const Eigen::Index n = plant.A.rows(), m = plant.B.cols(), p = C.rows();
  if (plant.A.cols() != n || plant.B.rows() != n || C.cols() != n)
    throw Error("augmentWithIntegrators: C must have as many columns as the plant has states");
  StateSpace aug;
  aug.A = MatX::Zero(n + p, n + p);
  aug.A.topLeftCorner(n, n) = plant.A;
  aug.A.bottomLeftCorner(p, n) = -C;  // x_i' = r - C x
  aug.B = MatX::Zero(n + p, m);
  aug.B.topRows(n) = plant.B;
  aug.Bref = MatX::Zero(n + p, p);
  aug.Bref.bottomRows(p).setIdentity();
  return aug;
}

StateSpace discretizeZoh(const StateSpace& c, double period) {
  if (!(period > 0.0) || !std::isfinite(period)) throw Error("discretizeZoh: period must be positive and finite");
  const Eigen::Index n = c.A.rows(), m = c.B.cols(), r = c.Bref.cols();
  if (c.A.cols() != n || c.B.rows() != n || (r > 0 && c.Bref.rows() != n))
    throw Error("discretizeZoh: inconsistent matrix sizes");
  if (!c.A.allFinite() || !c.B.allFinite() || !c.Bref.allFinite())
    throw Error("discretizeZoh: model contains NaN or Inf");
  // exp([[A, [B Bref]], [0, 0]] T) = [[Ad, int_0^T e^{A t} dt [B Bref]], [0, I]].
  MatX block = MatX::Zero(n + m + r, n + m + r);
  block.topLeftCorner(n, n) = c.A * period;
  block.block(0, n, n, m) = c.B * period;
  if (r > 0) block.block(0, n + m, n, r) = c.Bref * period;
  const MatX E = block.exp();
  StateSpace d;
  d.A = E.topLeftCorner(n, n);
  d.B = E.block(0, n, n, m);
  if (r > 0) d.Bref = E.block(0, n + m, n, r);
  // Any block can overflow on its own (e.g. a huge B next to a finite e^{AT}): check all of them.
  if (!d.A.allFinite() || !d.B.allFinite() || !d.Bref.allFinite())
    throw Error("discretizeZoh: matrix exponential overflowed");
  return d;
}

StateSpace augmentWithInputDelay(const StateSpace& d, int delay_samples) {
  if (delay_samples < 0) throw Error("augmentWithInputDelay: the delay must be >= 0 samples");
  const Eigen::Index n = d.A.rows(), m = d.B.cols(), r = d.Bref.cols();
  if (d.A.cols() != n || d.B.rows() != n || (r > 0 && d.Bref.rows() != n))
    throw Error("augmentWithInputDelay: inconsistent matrix sizes");
  if (delay_samples == 0) return d;
  const Eigen::Index D = delay_samples, na = n + D * m;
  StateSpace aug;
  aug.A = MatX::Zero(na, na);
  aug.A.topLeftCorner(n, n) = d.A;
  aug.A.block(0, n + (D - 1) * m, n, m) = d.B;  // the oldest command in flight acts now
  // Shift register: u_{k-j} of the next sample is u_{k-j+1} of this one.
  aug.A.block(n + m, n, (D - 1) * m, (D - 1) * m).setIdentity();
  aug.B = MatX::Zero(na, m);
  aug.B.block(n, 0, m, m).setIdentity();  // u_k enters the queue
  if (r > 0) {
    aug.Bref = MatX::Zero(na, r);
    aug.Bref.topRows(n) = d.Bref;
  }
  return aug;
}

double fastestPoleRadPerSecond(const MatX& A_closed_loop, double period) {
  const auto z = Eigen::EigenSolver<MatX>(A_closed_loop, false).eigenvalues();
  double fastest = 0.0;
  for (Eigen::Index i = 0; i < z.size(); ++i) {
    // z = exp(s T): |s| = |ln z| / T (a pole at z = 0 would be infinitely fast: cap at Nyquist-free value).
    const std::complex<double> s = std::log(z(i)) / period;
    if (std::isfinite(std::abs(s))) fastest = std::max(fastest, std::abs(s));
  }
  return fastest;
}

LqrDesign designLqrWithIntegrators(const LqrDesignRequest& req) {
  const Eigen::Index n = req.x0.size(), m = req.u0.size(), p = req.C.rows();
  if (req.C.cols() != n) throw Error("designLqrWithIntegrators: C must have one column per plant state");
  if (req.Q.rows() != n + p || req.Q.cols() != n + p) {
    std::ostringstream s;
    s << "designLqrWithIntegrators: Q must be " << n + p << "x" << n + p << " (plant + integral states), got "
      << req.Q.rows() << "x" << req.Q.cols();
    throw Error(s.str());
  }
  if (req.R.rows() != m || req.R.cols() != m) throw Error("designLqrWithIntegrators: R must be m x m");
  LqrDesign d;
  d.plant = linearize(req.dynamics, req.x0, req.u0);
  if (req.input_delay_samples < 0) throw Error("designLqrWithIntegrators: input_delay_samples must be >= 0");
  d.discrete = discretizeZoh(augmentWithIntegrators(d.plant, req.C), req.period);
  d.design_plant = augmentWithInputDelay(d.discrete, req.input_delay_samples);
  // The commands in flight carry no weight of their own: they are costed through the states they
  // move (and they are stable, nilpotent states, so (A, Q) stays detectable).
  const Eigen::Index na = d.design_plant.A.rows();
  MatX Q = MatX::Zero(na, na);
  Q.topLeftCorner(n + p, n + p) = req.Q;
  d.dare = solveDare(d.design_plant.A, d.design_plant.B, Q, req.R, req.dare);
  d.K = d.dare.K;
  d.Kc = d.K.leftCols(n);
  d.Ki = d.K.middleCols(n, p);
  d.Kd = d.K.rightCols(na - n - p);
  d.fastest_pole_rad_s = fastestPoleRadPerSecond(d.design_plant.A - d.design_plant.B * d.K, req.period);
  return d;
}

}  // namespace uhaptics
