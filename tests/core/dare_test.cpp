#include "uhaptics/core/dare.hpp"

#include <Eigen/Eigenvalues>
#include <array>
#include <catch2/catch.hpp>
#include <cmath>
#include <complex>

#include "uhaptics/core/decompositions.hpp"
#include "uhaptics/core/eigenvalues.hpp"
#include "uhaptics/core/fault.hpp"
#include "uhaptics/core/lqr_design.hpp"

using namespace uhaptics;

namespace {
MatX scalar(double v) { return MatX::Constant(1, 1, v); }
// Scalar DARE p = a^2 p - a^2 b^2 p^2 / (r + b^2 p) + q  <=>  b^2 p^2 + (r - a^2 r - q b^2) p - q r = 0.
double scalarDare(double a, double b, double q, double r) {
  const double B = r - a * a * r - q * b * b;
  return (-B + std::sqrt(B * B + 4.0 * b * b * q * r)) / (2.0 * b * b);
}
}  // namespace

TEST_CASE("DARE matches the closed-form scalar solution, stable and unstable plants") {
  for (double a : {0.5, 1.0, 1.2, -2.0})
    for (double q : {1e-3, 1.0, 1e6})
      for (double r : {1e-2, 1.0, 1e3}) {
        const double b = 0.7;
        const DareResult res = solveDare(scalar(a), scalar(b), scalar(q), scalar(r));
        const double p = scalarDare(a, b, q, r);
        INFO("a " << a << " q " << q << " r " << r);
        // Relative 1e-10: the closed form loses ~eps*cond digits for q/r = 1e8, still far below 1e-10.
        CHECK(res.P(0, 0) == Approx(p).epsilon(1e-10));
        CHECK(res.K(0, 0) == Approx(b * p * a / (r + b * b * p)).epsilon(1e-10));
        CHECK(res.closed_loop_spectral_radius < 1.0);
      }
}

TEST_CASE("DARE of a diagonal system is the diagonal of scalar solutions") {
  MatX A = VecX::LinSpaced(5, 0.3, 1.5).asDiagonal();
  MatX B = VecX::LinSpaced(5, 0.1, 2.0).asDiagonal();
  VecX qd(5), rd(5);
  qd << 1, 10, 1e3, 1e5, 1e7;
  rd << 1, 0.1, 1, 10, 1;
  const DareResult res = solveDare(A, B, MatX(qd.asDiagonal()), MatX(rd.asDiagonal()));
  for (int i = 0; i < 5; ++i) CHECK(res.P(i, i) == Approx(scalarDare(A(i, i), B(i, i), qd(i), rd(i))).epsilon(1e-10));
  CHECK((res.P - MatX(res.P.diagonal().asDiagonal())).norm() < 1e-9 * res.P.norm());
}

TEST_CASE("DARE stays accurate with weights spanning 1e0..1e9 on integrator chains") {
  // Discrete double integrators with an integral state (the TAU structure in miniature):
  // eigenvalues all at z = 1, Q weights 1 .. 1e9.
  const double T = 1e-3;
  for (double w : {1e0, 1e3, 1e6, 1e9}) {
    MatX A(3, 3), B(3, 1);
    A << 1, 0, 0, T, 1, 0, -0.5 * T * T, -T, 1;
    B << T / 0.03, 0.5 * T * T / 0.03, -T * T * T / 6 / 0.03;
    MatX Q = VecX((VecX(3) << 1.0, 1e3, w).finished()).asDiagonal();
    const DareResult res = solveDare(A, B, Q, MatX::Identity(1, 1));
    INFO("integral weight " << w << " residual " << res.relative_residual);
    CHECK(res.relative_residual < 1e-11);
    CHECK(res.closed_loop_spectral_radius < 1.0);
  }
}

TEST_CASE("DARE solves near-unstabilizable pairs and rejects unstabilizable/undetectable ones") {
  MatX A(2, 2), Q = MatX::Identity(2, 2), R = MatX::Identity(1, 1);
  A << 1.1, 0, 0, 0.5;
  MatX B(2, 1);
  SECTION("weakly controllable unstable mode: still solved, residual verified") {
    B << 1e-4, 1;
    const DareResult res = solveDare(A, B, Q, R);
    CHECK(res.relative_residual < 1e-9);
    CHECK(res.closed_loop_spectral_radius < 1.0);
  }
  SECTION("uncontrollable unstable mode") {
    B << 0, 1;
    REQUIRE_THROWS_AS(solveDare(A, B, Q, R), Error);
    CHECK_THROWS_WITH(solveDare(A, B, Q, R), Catch::Contains("not stabilizable"));
  }
  SECTION("unstable mode invisible to Q") {
    B << 1, 1;
    MatX Qs = MatX::Zero(2, 2);
    Qs(1, 1) = 1.0;
    CHECK_THROWS_WITH(solveDare(A, B, Qs, R), Catch::Contains("not detectable"));
  }
  SECTION("uncontrollable but stable mode is fine") {
    MatX As(2, 2);
    As << 0.9, 0, 0, 0.5;
    B << 0, 1;
    CHECK(solveDare(As, B, Q, R).relative_residual < 1e-12);
  }
  SECTION("malformed input") {
    B << 1, 1;
    CHECK_THROWS_WITH(solveDare(A, B, Q, -R), Catch::Contains("R is not positive definite"));
    MatX Qbad(2, 2);
    Qbad << 1, 0.5, 0, 1;
    CHECK_THROWS_WITH(solveDare(A, B, Qbad, R), Catch::Contains("not symmetric"));
    MatX Anan(2, 2);
    Anan << std::nan(""), 0, 0, 0.5;
    CHECK_THROWS_WITH(solveDare(Anan, B, Q, R), Catch::Contains("NaN"));
    CHECK_THROWS_WITH(solveDare(A, MatX::Ones(3, 1), Q, R), Catch::Contains("inconsistent sizes"));
  }
}

namespace {
// Independent reference: P from the stable invariant subspace of the symplectic matrix
// (Pappas, Laub & Sandell 1980), computed with Eigen's generic (non-symmetric) eigensolver:
//   Z = [A + G A^-T Q, -G A^-T; -A^-T Q, A^-T],  G = B R^-1 B^T,
//   Z [X1; X2] = [X1; X2] Lambda with |Lambda| < 1  ->  P = X2 X1^-1.
// A different algorithm from the doubling iteration under test (needs A invertible).
MatX symplecticDare(const MatX& A, const MatX& B, const MatX& Q, const MatX& R) {
  const Eigen::Index n = A.rows();
  const MatX Ait = A.transpose().inverse();
  const MatX G = B * R.inverse() * B.transpose();
  MatX Z(2 * n, 2 * n);
  Z << A + G * Ait * Q, -G * Ait, -Ait * Q, Ait;
  Eigen::VectorXcd values;
  Eigen::MatrixXcd vectors;
  REQUIRE(generalEigenvectors(Z, values, vectors));
  Eigen::MatrixXcd X(2 * n, n);
  Eigen::Index k = 0;
  for (Eigen::Index i = 0; i < 2 * n; ++i)
    if (std::abs(values(i)) < 1.0 && k < n) X.col(k++) = vectors.col(i);
  REQUIRE(k == n);  // a symplectic pencil without unit-circle eigenvalues splits n / n
  const Eigen::MatrixXcd P = X.bottomRows(n) * X.topRows(n).inverse();
  CHECK(P.imag().norm() < 1e-9 * P.real().norm());  // conjugate pairs give a real P
  return P.real();
}

// The plain Riccati recursion P <- A^T P A - A^T P B (R + B^T P B)^-1 B^T P A + Q from P = Q, run to
// convergence: slow (linear rate) but a second independent method that needs no invertible A.
MatX riccatiRecursion(const MatX& A, const MatX& B, const MatX& Q, const MatX& R, int& iterations) {
  MatX P = Q;
  for (iterations = 0; iterations < 200000; ++iterations) {
    const MatX BtP = B.transpose() * P;
    MatX next = A.transpose() * P * A - (BtP * A).transpose() * (R + BtP * B).ldlt().solve(BtP * A) + Q;
    next = 0.5 * (next + next.transpose());
    const double change = (next - P).norm();
    P = next;
    if (change <= 1e-15 * P.norm()) break;
  }
  return P;
}

// Discretized coupled 6-joint plant x = (qdot, q) with integral states of -q (the TAU structure):
// an assumed symmetric positive definite joint inertia with off-diagonal coupling (1e-3 kg m^2 scale).
StateSpace coupledJointPlant(double period) {
  MatX L = MatX::Zero(6, 6);
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j <= i; ++j) L(i, j) = 1e-2 * (1.0 + 0.3 * std::sin(1.7 * i + 0.9 * j));
  const MatX M = L * L.transpose() + 2e-3 * MatX::Identity(6, 6);
  StateSpace c;
  c.A = MatX::Zero(12, 12);
  c.A.bottomLeftCorner(6, 6).setIdentity();  // q' = qdot
  c.B = MatX::Zero(12, 6);
  c.B.topRows(6) = M.inverse();               // qdot' = M^-1 u
  MatX C = MatX::Zero(6, 12);
  C.rightCols(6).setIdentity();
  return discretizeZoh(augmentWithIntegrators(c, C), period);
}
}  // namespace

TEST_CASE("DARE matches the symplectic eigenvector solution on coupled, unstable MIMO plants") {
  // 4 states, 2 inputs, two unstable modes, full coupling, non-diagonal Q and R.
  MatX A(4, 4), B(4, 2), Q(4, 4), R(2, 2);
  A << 1.2, 0.3, -0.1, 0.0, 0.1, 0.9, 0.2, 0.05, 0.0, -0.3, 1.05, 0.1, 0.2, 0.0, 0.1, 0.6;
  B << 1.0, 0.0, 0.5, 0.3, 0.0, 1.0, 0.2, -0.4;
  MatX W(4, 4);
  W << 1, 0.2, 0, 0.1, 0, 2, 0.3, 0, 0.1, 0, 1, 0.2, 0, 0.1, 0, 3;
  Q = W.transpose() * W;
  R << 2.0, 0.3, 0.3, 1.0;
  const DareResult res = solveDare(A, B, Q, R);
  const MatX Pref = symplecticDare(A, B, Q, R);
  // Both are backward stable to ~1e-14 relative here (Z's eigenvalues are well separated from the
  // unit circle); 1e-10 leaves room for the eigenvector conditioning.
  CHECK((res.P - Pref).norm() < 1e-10 * Pref.norm());

  // 8 states, 3 inputs: a lightly damped oscillator chain (eigenvalues near the unit circle) with
  // one input per pair of states and a rank-deficient Q (detectable through the coupling).
  MatX A8 = MatX::Zero(8, 8), B8 = MatX::Zero(8, 3), Q8 = MatX::Zero(8, 8);
  for (int i = 0; i < 4; ++i) {
    const double w = 0.3 + 0.2 * i, rho = 0.98 + 0.015 * i;  // one mode at rho = 1.025: unstable
    A8.block<2, 2>(2 * i, 2 * i) << rho * std::cos(w), -rho * std::sin(w), rho * std::sin(w), rho * std::cos(w);
    if (i < 3) A8(2 * i + 2, 2 * i) = 0.1;  // chain coupling
  }
  B8(1, 0) = 1.0;
  B8(3, 1) = 0.5;
  B8(5, 1) = 0.7;
  B8(7, 2) = 1.0;
  B8(4, 0) = 0.2;
  for (int i = 0; i < 8; i += 2) Q8(i, i) = 1.0 + i;
  const MatX R8 = MatX::Identity(3, 3) * 0.5;
  const DareResult res8 = solveDare(A8, B8, Q8, R8);
  const MatX Pref8 = symplecticDare(A8, B8, Q8, R8);
  INFO("8-state chain: |P - P_ref| / |P_ref| = " << (res8.P - Pref8).norm() / Pref8.norm());
  CHECK((res8.P - Pref8).norm() < 1e-10 * Pref8.norm());
  // (The TAU-structure plant at 1 ms is compared with the Riccati recursion below instead: its
  // closed-loop eigenvalues and their reciprocals cluster at z ~ 1 +- 0.01, and there the
  // eigenvector route itself loses 4-7 digits; measured reference residual 4e-8 even at 20 ms.)
}

TEST_CASE("DARE on the hard case (integral weights 1e7 and 1e10) agrees with the Riccati recursion") {
  const StateSpace d = coupledJointPlant(1e-3);  // the servo period: fast velocity modes next to integrators
  for (const auto& w : {std::array<double, 3>{1.0, 1e3, 1e7}, std::array<double, 3>{1.1, 1e6, 1e10}}) {
    VecX qd(18);
    qd << VecX::Constant(6, w[0]), VecX::Constant(6, w[1]), VecX::Constant(6, w[2]);
    const MatX Q = qd.asDiagonal();
    const MatX R = MatX::Identity(6, 6);
    const DareResult res = solveDare(d.A, d.B, Q, R);
    int iterations = 0;
    const MatX Pref = riccatiRecursion(d.A, d.B, Q, R, iterations);
    INFO("weights " << w[0] << ", " << w[1] << ", " << w[2] << ": SDA " << res.iterations << " doublings, residual "
                    << res.relative_residual << "; recursion " << iterations << " steps");
    REQUIRE(iterations < 200000);
    CHECK(res.relative_residual < 1e-12);
    CHECK(dareRelativeResidual(d.A, d.B, Q, R, Pref) < 1e-12);
    // Two methods, one fixed point: they agree to the conditioning of the DARE, far below any
    // difference in the gain that would matter (1e-8 relative).
    CHECK((res.P - Pref).norm() < 1e-8 * Pref.norm());
    CHECK((res.K - (R + d.B.transpose() * Pref * d.B).ldlt().solve(d.B.transpose() * Pref * d.A)).norm() <
          1e-8 * res.K.norm());
  }
}

namespace {
// The plant of a weakly coupled integrator: x1' = x2, x2' = -w^2 x1 - 0.1 w x2 + u, x3' = -x1 with
// w = 1e4 rad/s, ZOH at 1 ms. u reaches x3 only through x1, whose static gain is 1 / w^2 = 1e-8, so
// in these units the integrator's column of [A - I, B] is small next to the velocity entries (1e3).
// `coupled` false gives its unstabilizable twin: the integrator not driven at all (x3' = 0), or, with
// `unstable_twin`, diverging on its own (x3' = 10 x3), both with |z| >= 1 and no input path.
StateSpace weakIntegratorPlant(bool coupled, bool unstable_twin = false) {
  const double w = 1e4;
  StateSpace c;
  c.A = MatX::Zero(3, 3);
  c.B = MatX::Zero(3, 1);
  c.A << 0, 1, 0, -w * w, -0.1 * w, 0, coupled ? -1.0 : 0.0, 0, unstable_twin ? 10.0 : 0.0;
  c.B << 0, 1, 0;
  return discretizeZoh(c, 1e-3);
}

using MatL = Eigen::Matrix<long double, Eigen::Dynamic, Eigen::Dynamic>;

// Independent reference: Hewer's iteration (Newton's method on the DARE) in long double. From a
// stabilizing K: solve the Lyapunov equation P = Acl^T P Acl + Q + K^T R K by its Kronecker form, then
// K <- (R + B^T P B)^-1 B^T P A. Converges quadratically from any stabilizing K; K = 0 is one here
// (the discrete integrator's eigenvalue is 1 - 4e-12). No doubling, no balancing, 64-bit mantissa.
MatL hewerDare(const MatX& A_, const MatX& B_, const MatX& Q_, const MatX& R_, int& iterations) {
  const MatL A = A_.cast<long double>(), B = B_.cast<long double>(), Q = Q_.cast<long double>(),
             R = R_.cast<long double>();
  const Eigen::Index n = A.rows();
  MatL K = MatL::Zero(B.cols(), n), P(n, n);
  for (iterations = 1; iterations <= 100; ++iterations) {
    const MatL Acl = A - B * K;
    const MatL rhs = Q + K.transpose() * R * K;
    MatL L = MatL::Identity(n * n, n * n);
    for (Eigen::Index i = 0; i < n; ++i)
      for (Eigen::Index j = 0; j < n; ++j)
        for (Eigen::Index k = 0; k < n; ++k)
          for (Eigen::Index l = 0; l < n; ++l) L(i * n + j, k * n + l) -= Acl(k, i) * Acl(l, j);  // (Acl^T P Acl)_ij
    Eigen::Matrix<long double, Eigen::Dynamic, 1> v(n * n);
    for (Eigen::Index i = 0; i < n; ++i)
      for (Eigen::Index j = 0; j < n; ++j) v(i * n + j) = rhs(i, j);
    // Partial pivoting: FullPivLU would call the 1 - A33^2 = 7e-12 pivot a rank loss (relative to 1e7).
    const Eigen::Matrix<long double, Eigen::Dynamic, 1> p = L.partialPivLu().solve(v);
    for (Eigen::Index i = 0; i < n; ++i)
      for (Eigen::Index j = 0; j < n; ++j) P(i, j) = p(i * n + j);
    P = 0.5L * (P + P.transpose()).eval();
    const MatL Knext = (R + B.transpose() * P * B).fullPivLu().solve(B.transpose() * P * A);
    const long double change = (Knext - K).norm() / Knext.norm();
    K = Knext;
    if (change < 1e-12L) break;  // quadratic: the next step would change K by ~1e-24, below its rounding
  }
  return P;
}
}  // namespace

TEST_CASE("DARE solves a weakly coupled integrator (static gain 1e-8 at w = 1e4 rad/s) and agrees with Hewer's "
          "iteration") {
  const StateSpace d = weakIntegratorPlant(true);
  const MatX Q = VecX((VecX(3) << 1.0, 1e3, 1e7).finished()).asDiagonal();
  const MatX R = MatX::Identity(1, 1);
  const DareResult res = solveDare(d.A, d.B, Q, R);
  int iterations = 0;
  const MatL Pref = hewerDare(d.A, d.B, Q, R, iterations);
  const MatX Pd = Pref.cast<double>();
  // Residual of the equation in the caller's units, relative to |P|: each term is O(|P|) and rounds
  // to ~1e-16 |P|; 1e-9 is the solver's own acceptance bound (1e-8 on its normalization) tightened
  // by the factor |P| / (|Q| + |A^T P A|) ~ 1 of this plant. Measured 3e-20 (P11 dominates).
  const MatX BtPA = d.B.transpose() * res.P * d.A;
  const MatX rhs = d.A.transpose() * res.P * d.A - BtPA.transpose() * (R + d.B.transpose() * res.P * d.B).ldlt().solve(BtPA) + Q;
  const double residual = (res.P - rhs).norm() / res.P.norm();
  VecX p_eigen;
  REQUIRE(symmetricEigen(res.P, p_eigen));
  const double p_min = p_eigen.minCoeff();
  const double agreement = (res.P - Pd).norm() / Pd.norm();
  INFO("SDA " << res.iterations << " doublings, residual/|P| " << residual << ", closed-loop radius "
              << res.closed_loop_spectral_radius << ", Hewer " << iterations << " steps, |P - P_ref|/|P_ref| "
              << agreement << ", |P| " << res.P.norm());
  REQUIRE(iterations <= 100);
  CHECK(residual < 1e-9);
  CHECK((res.P - res.P.transpose()).norm() == 0.0);
  CHECK(p_min > 0.0);
  CHECK(res.closed_loop_spectral_radius < 1.0);
  // The closed loop's slowest pole is 1 - 3e-8, so the DARE's condition is ~1 / (1 - rho^2) ~ 2e7:
  // double rounding (1e-16) allows ~2e-9 relative in P. Measured 1.3e-10; 1e-8 leaves a factor 5.
  CHECK(agreement < 1e-8);
}

TEST_CASE("DARE verdicts on the weakly coupled integrator and its unstabilizable twins do not depend on the state "
          "units (diagonal similarities 1e-6..1e6)") {
  const MatX Q = VecX((VecX(3) << 1.0, 1e3, 1e7).finished()).asDiagonal();
  const MatX R = MatX::Identity(1, 1);
  const StateSpace solvable = weakIntegratorPlant(true);
  const MatX P0 = solveDare(solvable.A, solvable.B, Q, R).P;
  const std::array<double, 5> exponents{-6, -3, 0, 3, 6};
  for (double e0 : exponents)
    for (double e1 : exponents)
      for (double e2 : exponents) {
        // x' = S x: A' = S A S^-1, B' = S B, Q' = S^-1 Q S^-1, and the exact P' = S^-1 P S^-1.
        const VecX s = (VecX(3) << std::pow(10.0, e0), std::pow(10.0, e1), std::pow(10.0, e2)).finished();
        const auto S = s.asDiagonal();
        const auto Si = s.cwiseInverse().asDiagonal();
        const MatX Qs = Si * Q * Si;
        INFO("state scales 1e" << e0 << ", 1e" << e1 << ", 1e" << e2);
        const DareResult res = solveDare(S * solvable.A * Si, S * solvable.B, Qs, R);
        // Back in the original units. The scaled plant is the original one rounded entrywise (S is
        // not a power of two), a 1e-16 relative perturbation times the condition ~2e7 (test above).
        CHECK((S * res.P * S - P0).norm() < 1e-8 * P0.norm());
        CHECK(res.closed_loop_spectral_radius < 1.0);
        for (bool unstable : {false, true}) {
          const StateSpace twin = weakIntegratorPlant(false, unstable);
          CHECK_THROWS_WITH(solveDare(S * twin.A * Si, S * twin.B, Qs, R),
                            Catch::Contains("DARE: (A, B) is not stabilizable") &&
                                Catch::Contains("no stabilizing LQR gain exists"));
        }
        // With the integrator unweighted the pair is not detectable and must be refused in any units.
        // Which test names it depends on the units: without a weight nothing fixes the integrator's
        // scale in the balancing, so its weak input coupling may be judged first.
        MatX Qd = Qs;
        Qd(2, 2) = 0.0;
        CHECK_THROWS_AS(solveDare(S * solvable.A * Si, S * solvable.B, Qd, R), Error);
      }
}
