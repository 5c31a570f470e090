#include "uhaptics/core/lqr_design.hpp"

#include <Eigen/LU>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <vector>

#include "uhaptics/core/eigenvalues.hpp"
#include "uhaptics/core/fault.hpp"

using namespace uhaptics;

TEST_CASE("ZOH of a double integrator and of a first-order lag match the analytic formulas") {
  const double T = 1e-3, m = 0.03;
  StateSpace c;
  c.A = MatX::Zero(2, 2);
  c.A(1, 0) = 1.0;  // x = (v, p)
  c.B = MatX::Zero(2, 1);
  c.B(0, 0) = 1.0 / m;
  const StateSpace d = discretizeZoh(c, T);
  CHECK(d.A(1, 0) == Approx(T).epsilon(1e-14));
  CHECK(d.B(0, 0) == Approx(T / m).epsilon(1e-14));
  CHECK(d.B(1, 0) == Approx(T * T / (2 * m)).epsilon(1e-12));

  StateSpace lag;
  lag.A = MatX::Constant(1, 1, -50.0);
  lag.B = MatX::Constant(1, 1, 2.0);
  const StateSpace dl = discretizeZoh(lag, T);
  CHECK(dl.A(0, 0) == Approx(std::exp(-50.0 * T)).epsilon(1e-14));
  CHECK(dl.B(0, 0) == Approx(2.0 * (1 - std::exp(-50.0 * T)) / 50.0).epsilon(1e-12));
  CHECK_THROWS_AS(discretizeZoh(lag, -1.0), Error);
}

TEST_CASE("Augmentation adds x_i' = r - C x and the reference input (paper eq. 7)") {
  StateSpace c;
  c.A = MatX::Identity(2, 2);
  c.B = MatX::Ones(2, 1);
  MatX C(1, 2);
  C << 0, 1;
  const StateSpace a = augmentWithIntegrators(c, C);
  REQUIRE(a.A.rows() == 3);
  CHECK(a.A(2, 1) == -1.0);
  CHECK(a.A(2, 0) == 0.0);
  CHECK(a.Bref(2, 0) == 1.0);
  CHECK(a.B(2, 0) == 0.0);
}

TEST_CASE("Linearization reproduces the Jacobians of a pendulum") {
  // x = (omega, theta), omega' = -g/l sin(theta) - c omega + u / (m l^2)
  const double g = 9.81, l = 0.2, cdamp = 0.3, mass = 0.5;
  DynamicsFunction f = [&](const VecX& x, const VecX& u, VecX& xd) {
    xd.resize(2);
    xd(0) = -g / l * std::sin(x(1)) - cdamp * x(0) + u(0) / (mass * l * l);
    xd(1) = x(0);
  };
  VecX x0(2), u0(1);
  x0 << 0.4, 0.7;
  u0 << 0.1;
  const StateSpace s = linearize(f, x0, u0);
  // Central differences: truncation O(h^2) with h ~ 6e-6: 1e-8 relative is safe.
  CHECK(s.A(0, 1) == Approx(-g / l * std::cos(0.7)).epsilon(1e-8));
  CHECK(s.A(0, 0) == Approx(-cdamp).epsilon(1e-8));
  CHECK(s.A(1, 0) == Approx(1.0).epsilon(1e-10));
  CHECK(s.B(0, 0) == Approx(1.0 / (mass * l * l)).epsilon(1e-8));
}

TEST_CASE("Full LQR-with-integrator design on a scalar mass: gain and fastest pole") {
  LqrDesignRequest req;
  const double m = 0.03;
  req.dynamics = [m](const VecX& x, const VecX& u, VecX& xd) {
    xd.resize(2);
    xd << u(0) / m, x(0);
  };
  req.x0 = VecX::Zero(2);
  req.u0 = VecX::Zero(1);
  req.C = MatX(1, 2);
  req.C << 0, 1;
  req.Q = VecX((VecX(3) << 1.0, 1e3, 1e7).finished()).asDiagonal();
  req.R = MatX::Identity(1, 1);
  const LqrDesign d = designLqrWithIntegrators(req);
  CHECK(d.dare.relative_residual < 1e-10);
  CHECK(d.K.cols() == 3);
  CHECK(d.Kc.cols() == 2);
  CHECK(d.Ki.cols() == 1);
  // Ki < 0 with this sign convention: x_i integrates r - q, u = -K x.
  CHECK(d.Ki(0, 0) < 0.0);
  CHECK(d.fastest_pole_rad_s > 10.0);  // measured ~50 rad/s for this light weighting
  CHECK(d.fastest_pole_rad_s < M_PI / req.period);
  CHECK_THROWS_WITH(
      [&] {
        LqrDesignRequest bad = req;
        bad.Q = MatX::Identity(2, 2);
        designLqrWithIntegrators(bad);
      }(),
      Catch::Contains("Q must be 3x3"));
}


TEST_CASE("Input-delay augmentation: closed form for a scalar plant and a stable delayed loop") {
  // x+ = a x + b u_{k-1}: state (x, u_{k-1}), A = [[a, b], [0, 0]], B = [0; 1].
  const double a = 1.5, b = 1.0;
  StateSpace plant;
  plant.A = MatX::Constant(1, 1, a);
  plant.B = MatX::Constant(1, 1, b);
  plant.Bref = MatX::Constant(1, 1, 0.25);
  const StateSpace d = augmentWithInputDelay(plant, 1);
  MatX A_expected(2, 2), B_expected(2, 1), Bref_expected(2, 1);
  A_expected << a, b, 0, 0;
  B_expected << 0, 1;
  Bref_expected << 0.25, 0;  // the reference is internal to the controller: not delayed
  CHECK(d.A == A_expected);
  CHECK(d.B == B_expected);
  CHECK(d.Bref == Bref_expected);

  // A stiff design (q >> r) on the undelayed plant nearly cancels a: K0 -> a / b. On the true
  // delayed plant u_k = -K0 x_k gives z^2 - a z + b K0 = 0, whose roots multiply to b K0 ~ 1.5:
  // unstable. The design on the augmented plant accounts for the sample in flight: stable.
  const MatX Q = MatX::Constant(1, 1, 1e6), R = MatX::Identity(1, 1);
  const DareResult undelayed = solveDare(plant.A, plant.B, Q, R);
  const double K0 = undelayed.K(0, 0);
  CHECK(K0 == Approx(a / b).epsilon(1e-5));
  MatX loop_undelayed = d.A;
  loop_undelayed.row(1) = -K0 * MatX::Identity(1, 2).row(0);  // u_k = -K0 x_k enters the queue
  CHECK(spectralRadius(loop_undelayed) > 1.2);

  MatX Qa = MatX::Zero(2, 2);
  Qa(0, 0) = 1e6;  // the command in flight carries no weight of its own
  const DareResult delayed = solveDare(d.A, d.B, Qa, R);
  CHECK(spectralRadius(d.A - d.B * delayed.K) < 1.0);
  // With q >> r the delayed design is deadbeat for x: u_k = -(a^2 x_k + a b u_{k-1}) / b makes
  // x_{k+2} = 0 (closed form of the one-step predictor a x_k + b u_{k-1} = x_{k+1}).
  CHECK(delayed.K(0, 0) == Approx(a * a / b).epsilon(1e-5));
  CHECK(delayed.K(0, 1) == Approx(a).epsilon(1e-5));
}

TEST_CASE("Input-delay augmentation: shift-register structure for a MIMO plant, D = 0 unchanged") {
  StateSpace plant;
  plant.A = MatX::Random(3, 3);
  plant.B = MatX::Random(3, 2);
  const StateSpace same = augmentWithInputDelay(plant, 0);
  CHECK(same.A == plant.A);
  CHECK(same.B == plant.B);
  const int D = 3;
  const StateSpace d = augmentWithInputDelay(plant, D);
  REQUIRE(d.A.rows() == 3 + D * 2);
  REQUIRE(d.B.cols() == 2);
  // Propagate a command pulse: it must reach x exactly D samples later, through B.
  VecX s = VecX::Zero(3 + D * 2);
  VecX u(2);
  u << 1.0, -2.0;
  s = d.B * u;  // u_0 issued at k = 0
  for (int k = 1; k < D; ++k) {
    CHECK(s.head(3).isZero());
    s = d.A * s;
  }
  CHECK(s.head(3).isZero());
  s = d.A * s;  // the pulse acts over sample D
  CHECK((s.head(3) - plant.B * u).norm() < 1e-15);
  CHECK(s.tail(D * 2).isZero());
  CHECK_THROWS_AS(augmentWithInputDelay(plant, -1), Error);
  StateSpace bad = plant;
  bad.B = MatX::Zero(2, 2);
  CHECK_THROWS_AS(augmentWithInputDelay(bad, 1), Error);
}

namespace {
// Spectral radius of the second-moment map sum p_i F_i (x) F_i: the exact mean-square test for small n.
double kroneckerMsRadius(const std::vector<MatX>& F, const std::vector<double>& p) {
  const Eigen::Index n = F[0].rows();
  MatX M = MatX::Zero(n * n, n * n);
  for (std::size_t i = 0; i < F.size(); ++i)
    for (Eigen::Index r = 0; r < n; ++r)
      for (Eigen::Index c = 0; c < n; ++c) M.block(r * n, c * n, n, n) += p[i] * F[i](r, c) * F[i];
  return spectralRadius(M);
}

// Expected cost E sum_k (z^T Q z + u^T R u + 2 z^T N u) of u = -K z from z0, by the exact
// second-moment recursion X+ = sum p F X F^T (no sampling), summed until it has decayed.
double expectedCost(const std::vector<MatX>& A, const std::vector<MatX>& B, const std::vector<double>& p,
                    const MatX& Q, const MatX& R, const MatX& N, const MatX& K, const VecX& z0) {
  const MatX stage = Q + K.transpose() * R * K - N * K - K.transpose() * N.transpose();
  MatX X = z0 * z0.transpose();
  double cost = 0.0;
  for (int k = 0; k < 20000; ++k) {
    cost += (stage * X).trace();
    MatX next = MatX::Zero(X.rows(), X.cols());
    for (std::size_t i = 0; i < A.size(); ++i) {
      const MatX F = A[i] - B[i] * K;
      next += p[i] * F * X * F.transpose();
    }
    X = next;
    if (X.norm() < 1e-300) break;
  }
  return cost;
}
}  // namespace

TEST_CASE("Random-parameter LQR: scalar closed form, and the deterministic DARE as a special case") {
  // x+ = a x + b_i u, P[i] = p_i. The generalized Riccati equation is a quadratic in P:
  //   P = q + a^2 P - (a P Eb)^2 / (r + P Eb2)
  //   (Eb2 (1 - a^2) + a^2 Eb^2) P^2 + (r (1 - a^2) - q Eb2) P - q r = 0,  P > 0 the root.
  const double a = 1.2, q = 2.0, r = 0.5;
  const std::vector<double> b = {0.0, 0.6, 1.5}, p = {0.3, 0.3, 0.4};
  double Eb = 0, Eb2 = 0;
  std::vector<MatX> As, Bs;
  for (std::size_t i = 0; i < b.size(); ++i) {
    Eb += p[i] * b[i];
    Eb2 += p[i] * b[i] * b[i];
    As.push_back(MatX::Constant(1, 1, a));
    Bs.push_back(MatX::Constant(1, 1, b[i]));
  }
  const double c2 = Eb2 * (1 - a * a) + a * a * Eb * Eb, c1 = r * (1 - a * a) - q * Eb2, c0 = -q * r;
  const double P = (-c1 + std::sqrt(c1 * c1 - 4 * c2 * c0)) / (2 * c2);
  const RandomParameterLqrResult res =
      solveRandomParameterLqr(As, Bs, p, MatX::Constant(1, 1, q), MatX::Constant(1, 1, r));
  CHECK(res.P(0, 0) == Approx(P).epsilon(1e-10));
  CHECK(res.K(0, 0) == Approx(a * P * Eb / (r + P * Eb2)).epsilon(1e-10));
  CHECK(res.relative_residual < 1e-12);
  // Mean square: E[(a - b K)^2] < 1, the closed form of the scalar second-moment map.
  double ms = 0;
  for (std::size_t i = 0; i < b.size(); ++i) ms += p[i] * std::pow(a - b[i] * res.K(0, 0), 2);
  CHECK(res.mean_square_spectral_radius == Approx(ms).epsilon(1e-9));
  CHECK(ms < 1.0);
  // The mean system alone (b = Eb always) would be stabilized by a gain the random system rejects:
  // the certainty-equivalent gain is more aggressive.
  const DareResult mean = solveDare(MatX::Constant(1, 1, a), MatX::Constant(1, 1, Eb), MatX::Constant(1, 1, q),
                                    MatX::Constant(1, 1, r));
  CHECK(mean.K(0, 0) > res.K(0, 0));

  // One mode with probability 1 and a cross term: the DARE of the transformed problem
  // (A - B R^-1 N^T, Q - N R^-1 N^T) is the same LQR.
  const MatX A = (MatX(2, 2) << 1.0, 0.1, 0.0, 1.0).finished(), Bm = (MatX(2, 1) << 0.005, 0.1).finished();
  const MatX Qm = (MatX(2, 2) << 3.0, 0.2, 0.2, 1.0).finished(), Rm = MatX::Constant(1, 1, 2.0);
  const MatX N = (MatX(2, 1) << 0.4, -0.3).finished();
  const RandomParameterLqrResult one = solveRandomParameterLqr({A}, {Bm}, {1.0}, Qm, Rm, N);
  const MatX Rinv = Rm.inverse();
  const DareResult ref = solveDare(A - Bm * Rinv * N.transpose(), Bm, Qm - N * Rinv * N.transpose(), Rm);
  CHECK((one.P - ref.P).norm() < 1e-8 * ref.P.norm());
  CHECK((one.K - (ref.K + Rinv * N.transpose())).norm() < 1e-8 * one.K.norm());

  CHECK_THROWS_AS(solveRandomParameterLqr(As, Bs, {0.5, 0.5, 0.5}, MatX::Ones(1, 1), MatX::Ones(1, 1)), Error);
  CHECK_THROWS_AS(solveRandomParameterLqr(As, {Bs[0], Bs[1]}, p, MatX::Ones(1, 1), MatX::Ones(1, 1)), Error);
  // Not mean-square stabilizable: a = 3 with an input that is absent half of the time
  // (E[(a - b K)^2] >= 0.5 a^2 > 1 for every K).
  CHECK_THROWS_AS(solveRandomParameterLqr({MatX::Constant(1, 1, 3.0), MatX::Constant(1, 1, 3.0)},
                                          {MatX::Zero(1, 1), MatX::Ones(1, 1)}, {0.5, 0.5}, MatX::Ones(1, 1),
                                          MatX::Ones(1, 1)),
                  Error);
}

TEST_CASE("Random input delay: modes, optimality by brute-force expected cost, mean-square stability") {
  // An unstable 2-state plant, input delayed by d ~ U{0, 1, 2} each sample.
  StateSpace plant;
  plant.A = (MatX(2, 2) << 1.02, 0.05, 0.0, 0.98).finished();
  plant.B = (MatX(2, 1) << 0.0, 0.05).finished();
  const int D = 2;
  const std::vector<StateSpace> modes = randomInputDelayModes(plant, D);
  REQUIRE(modes.size() == 3);
  // Mode d applies u_{k-d}: with u_k = 1, u_{k-1} = 2, u_{k-2} = 3 queued, x+ = A x + B u_{k-d};
  // every mode shifts the queue alike.
  VecX z(4);
  z << 0.1, -0.2, 2.0, 3.0;
  const VecX u = VecX::Constant(1, 1.0);
  for (int d = 0; d <= D; ++d) {
    const VecX next = modes[d].A * z + modes[d].B * u;
    const double applied = d == 0 ? 1.0 : z(1 + d);
    CHECK((next.head(2) - (plant.A * z.head(2) + plant.B * applied)).norm() < 1e-15);
    CHECK(next(2) == 1.0);
    CHECK(next(3) == 2.0);
  }
  CHECK_THROWS_AS(randomInputDelayModes(plant, 0), Error);

  std::vector<MatX> As, Bs;
  for (const StateSpace& m : modes) {
    As.push_back(m.A);
    Bs.push_back(m.B);
  }
  const std::vector<double> p(3, 1.0 / 3.0);
  MatX Q = MatX::Zero(4, 4);
  Q.topLeftCorner(2, 2) = MatX::Identity(2, 2) * 10.0;
  const MatX R = MatX::Identity(1, 1);
  // Input-rate weight w (u_k - u_{k-1})^2: Q += S^T w S, R += w, N = -S^T w (S picks u_{k-1}).
  const double w = 5.0;
  MatX Qw = Q, Rw = R + MatX::Identity(1, 1) * w, N = MatX::Zero(4, 1);
  Qw(2, 2) += w;
  N(2, 0) = -w;
  for (const bool rate : {false, true}) {
    INFO("rate weight " << rate);
    const MatX& Qc = rate ? Qw : Q;
    const MatX& Rc = rate ? Rw : R;
    const MatX Nc = rate ? N : MatX::Zero(4, 1);
    const RandomParameterLqrResult res = solveRandomParameterLqr(As, Bs, p, Qc, Rc, Nc);
    CHECK(res.relative_residual < 1e-12);
    // Mean-square stability: the power-iteration estimate against the exact Kronecker test.
    std::vector<MatX> F;
    for (std::size_t i = 0; i < As.size(); ++i) F.push_back(As[i] - Bs[i] * res.K);
    const double exact = kroneckerMsRadius(F, p);
    CHECK(exact < 1.0);
    CHECK(res.mean_square_spectral_radius == Approx(exact).epsilon(1e-3));
    // Brute force: the exact expected cost from z0 is z0^T P z0, and every perturbed gain costs more.
    VecX z0(4);
    z0 << 1.0, -0.5, 0.3, 0.0;
    const double J = expectedCost(As, Bs, p, Qc, Rc, Nc, res.K, z0);
    CHECK(J == Approx(z0.dot(res.P * z0)).epsilon(1e-8));
    std::srand(7);
    for (int t = 0; t < 20; ++t) {
      const MatX K = res.K + 0.02 * res.K.norm() * MatX::Random(1, 4);
      CHECK(expectedCost(As, Bs, p, Qc, Rc, Nc, K, z0) > J);
    }
    // The gain designed for the fixed mean delay (1 sample) is worse under the random delay.
    if (!rate) {
      const StateSpace fixed = augmentWithInputDelay(plant, 1);
      MatX Qf = MatX::Zero(3, 3);
      Qf.topLeftCorner(2, 2) = Q.topLeftCorner(2, 2);
      const DareResult d1 = solveDare(fixed.A, fixed.B, Qf, R);
      MatX K1 = MatX::Zero(1, 4);
      K1.leftCols(3) = d1.K;
      CHECK(expectedCost(As, Bs, p, Q, R, Nc, K1, z0) > J);
    }
  }
}
