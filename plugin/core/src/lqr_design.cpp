#include "uhaptics/core/lqr_design.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <sstream>
#include <unsupported/Eigen/MatrixFunctions>

#include "uhaptics/core/eigenvalues.hpp"
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
  Eigen::VectorXcd z;
  if (!generalEigenvalues(A_closed_loop, z)) return std::numeric_limits<double>::quiet_NaN();
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
  MatX R = req.R, N;
  if (req.input_rate_weight.size() > 0) {
    const MatX& W = req.input_rate_weight;
    if (W.rows() != m || W.cols() != m) throw Error("designLqrWithIntegrators: the input-rate weight must be m x m");
    if (req.input_delay_samples < 1) throw Error("designLqrWithIntegrators: the input-rate weight needs a delay state (D >= 1)");
    // (u_k - S z)^T W (u_k - S z), S z = u_{k-1}: Q += S^T W S, R += W, cross term N = -S^T W.
    Q.block(n + p, n + p, m, m) += W;
    R += W;
    N = MatX::Zero(na, m);
    N.block(n + p, 0, m, m) = -W;
  }
  if (req.random_input_delay) {
    if (req.input_delay_samples < 1) throw Error("designLqrWithIntegrators: a random delay needs D >= 1");
    const std::vector<StateSpace> modes = randomInputDelayModes(d.discrete, req.input_delay_samples);
    std::vector<MatX> As, Bs;
    for (const StateSpace& mode : modes) {
      As.push_back(mode.A);
      Bs.push_back(mode.B);
    }
    const std::vector<double> prob(modes.size(), 1.0 / static_cast<double>(modes.size()));
    d.random = solveRandomParameterLqr(As, Bs, prob, Q, R, N, req.random_options);
    d.K = d.random.K;
    MatX mean_cl = MatX::Zero(na, na);
    for (std::size_t i = 0; i < modes.size(); ++i) mean_cl += prob[i] * (As[i] - Bs[i] * d.K);
    d.fastest_pole_rad_s = fastestPoleRadPerSecond(mean_cl, req.period);
  } else {
    if (N.size() > 0) throw Error("designLqrWithIntegrators: the input-rate weight is implemented for random delays only");
    d.dare = solveDare(d.design_plant.A, d.design_plant.B, Q, R, req.dare);
    d.K = d.dare.K;
    d.fastest_pole_rad_s = fastestPoleRadPerSecond(d.design_plant.A - d.design_plant.B * d.K, req.period);
  }
  d.Kc = d.K.leftCols(n);
  d.Ki = d.K.middleCols(n, p);
  d.Kd = d.K.rightCols(na - n - p);
  return d;
}

}  // namespace uhaptics

namespace uhaptics {

std::vector<StateSpace> randomInputDelayModes(const StateSpace& d, int max_delay) {
  if (max_delay < 1) throw Error("randomInputDelayModes: the largest delay must be >= 1 sample");
  const StateSpace fixed = augmentWithInputDelay(d, max_delay);  // checks sizes; mode max_delay
  const Eigen::Index n = d.A.rows(), m = d.B.cols();
  std::vector<StateSpace> modes;
  for (int delay = 0; delay <= max_delay; ++delay) {
    StateSpace mode = fixed;
    mode.A.block(0, n, n, max_delay * m).setZero();
    if (delay == 0) mode.B.topRows(n) = d.B;  // u_k acts now (and still enters the queue)
    else mode.A.block(0, n + (delay - 1) * m, n, m) = d.B;
    modes.push_back(std::move(mode));
  }
  return modes;
}

namespace {

void checkRandomParameterInput(const std::vector<MatX>& A, const std::vector<MatX>& B, const std::vector<double>& p,
                               const MatX& Q, const MatX& R, const MatX& N) {
  if (A.empty() || A.size() != B.size() || A.size() != p.size())
    throw Error("solveRandomParameterLqr: need one A, one B and one probability per mode");
  const Eigen::Index n = A[0].rows(), m = B[0].cols();
  double sum = 0.0;
  for (std::size_t i = 0; i < A.size(); ++i) {
    if (A[i].rows() != n || A[i].cols() != n || B[i].rows() != n || B[i].cols() != m)
      throw Error("solveRandomParameterLqr: inconsistent mode sizes");
    if (!A[i].allFinite() || !B[i].allFinite()) throw Error("solveRandomParameterLqr: mode contains NaN or Inf");
    if (!(p[i] >= 0.0)) throw Error("solveRandomParameterLqr: probabilities must be >= 0");
    sum += p[i];
  }
  if (std::abs(sum - 1.0) > 1e-12) throw Error("solveRandomParameterLqr: probabilities must sum to 1");
  if (Q.rows() != n || Q.cols() != n || R.rows() != m || R.cols() != m || (N.size() > 0 && (N.rows() != n || N.cols() != m)))
    throw Error("solveRandomParameterLqr: Q must be n x n, R m x m, N n x m");
  if (!Q.allFinite() || !R.allFinite() || !N.allFinite()) throw Error("solveRandomParameterLqr: weights contain NaN or Inf");
}

// The expectations E[A^T P A], E[A^T P B] (+ N), R + E[B^T P B] of one Riccati step.
struct RiccatiTerms {
  MatX AtPA, AtPB, H;
};
RiccatiTerms riccatiTerms(const std::vector<MatX>& A, const std::vector<MatX>& B, const std::vector<double>& p,
                          const MatX& R, const MatX& N, const MatX& P) {
  RiccatiTerms t;
  const Eigen::Index n = A[0].rows(), m = B[0].cols();
  t.AtPA = MatX::Zero(n, n);
  t.AtPB = N.size() > 0 ? N : MatX::Zero(n, m);
  t.H = R;
  MatX PA(n, n), PB(n, m);
  for (std::size_t i = 0; i < A.size(); ++i) {
    if (p[i] == 0.0) continue;
    PA.noalias() = P * A[i];
    PB.noalias() = P * B[i];
    t.AtPA.noalias() += p[i] * A[i].transpose() * PA;
    t.AtPB.noalias() += p[i] * A[i].transpose() * PB;
    t.H.noalias() += p[i] * B[i].transpose() * PB;
  }
  return t;
}

// Q + E[A^T P A] - (E[A^T P B] + N) H^-1 (...)^T, and the gain H^-1 (E[B^T P A] + N^T).
MatX riccatiStep(const RiccatiTerms& t, const MatX& Q, MatX* K) {
  Eigen::LLT<MatX> llt(t.H);
  if (llt.info() != Eigen::Success) throw Error("solveRandomParameterLqr: R + E[B^T P B] is not positive definite");
  MatX gain = llt.solve(t.AtPB.transpose());
  MatX next = Q + t.AtPA - t.AtPB * gain;
  next = 0.5 * (next + next.transpose()).eval();
  if (K) *K = std::move(gain);
  return next;
}

}  // namespace

double randomParameterRiccatiResidual(const std::vector<MatX>& A, const std::vector<MatX>& B,
                                      const std::vector<double>& p, const MatX& Q, const MatX& R, const MatX& N,
                                      const MatX& P) {
  checkRandomParameterInput(A, B, p, Q, R, N);
  const RiccatiTerms t = riccatiTerms(A, B, p, R, N, P);
  const MatX next = riccatiStep(t, Q, nullptr);
  return (P - next).norm() / std::max(Q.norm() + t.AtPA.norm(), std::numeric_limits<double>::min());
}

double meanSquareSpectralRadius(const std::vector<MatX>& F, const std::vector<double>& p, int iterations) {
  if (F.empty() || F.size() != p.size() || iterations < 1) throw Error("meanSquareSpectralRadius: bad input");
  const Eigen::Index n = F[0].rows();
  MatX X = MatX::Identity(n, n) / std::sqrt(static_cast<double>(n)), next(n, n);
  // Geometric mean of the growth over the last half (the first half lets the dominant mode win).
  double log_growth = 0.0;
  int counted = 0;
  for (int k = 0; k < iterations; ++k) {
    next.setZero();
    for (std::size_t i = 0; i < F.size(); ++i) next.noalias() += p[i] * F[i] * X * F[i].transpose();
    const double norm = next.norm();
    if (!(norm > 0.0)) return 0.0;  // nilpotent in mean square
    if (!std::isfinite(norm)) return std::numeric_limits<double>::infinity();
    if (k >= iterations / 2) {
      log_growth += std::log(norm);
      ++counted;
    }
    X = next / norm;
  }
  return std::exp(log_growth / counted);
}

RandomParameterLqrResult solveRandomParameterLqr(const std::vector<MatX>& A, const std::vector<MatX>& B,
                                                 const std::vector<double>& p, const MatX& Q, const MatX& R,
                                                 const MatX& N, const RandomParameterLqrOptions& options) {
  checkRandomParameterInput(A, B, p, Q, R, N);
  RandomParameterLqrResult out;
  const Eigen::Index n = A[0].rows();
  MatX P = MatX::Zero(n, n);
  bool converged = false;
  for (int k = 0; k < options.max_iterations; ++k) {
    MatX next = riccatiStep(riccatiTerms(A, B, p, R, N, P), Q, nullptr);
    if (!next.allFinite()) throw Error("solveRandomParameterLqr: the Riccati iteration diverged (not mean-square stabilizable?)");
    const double change = (next - P).norm() / std::max(next.norm(), std::numeric_limits<double>::min());
    P = std::move(next);
    out.iterations = k + 1;
    if (change < options.tolerance) {
      converged = true;
      break;
    }
  }
  if (!converged) throw Error("solveRandomParameterLqr: the Riccati iteration did not converge");
  riccatiStep(riccatiTerms(A, B, p, R, N, P), Q, &out.K);
  out.P = P;
  out.relative_residual = randomParameterRiccatiResidual(A, B, p, Q, R, N, P);
  if (!(out.relative_residual <= options.max_relative_residual))
    throw Error("solveRandomParameterLqr: residual check failed");
  std::vector<MatX> F;
  for (std::size_t i = 0; i < A.size(); ++i) F.push_back(A[i] - B[i] * out.K);
  out.mean_square_spectral_radius = meanSquareSpectralRadius(F, p);
  if (!(out.mean_square_spectral_radius < 1.0)) throw Error("solveRandomParameterLqr: the closed loop is not mean-square stable");
  return out;
}

}  // namespace uhaptics
