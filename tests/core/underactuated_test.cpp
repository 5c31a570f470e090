// The generic underactuated-rendering math (paper 000) against hand-derived closed forms, and the
// theoretical impedances against finite differences where the paper's approximations hold exactly.
#include "uhaptics/core/underactuated.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <limits>

#include "uhaptics/core/finite_difference.hpp"
#include "uhaptics/core/subspace_proxy_solver.hpp"
#include "uhaptics/tools/alloc_probe.hpp"

using namespace uhaptics;
namespace ua = uhaptics::underactuated;

namespace {
// J = [[2, 1], [0, 1]], one actuator on joint 0: small enough to do every formula by hand.
Mat2 handJ() { return (Mat2() << 2.0, 1.0, 0.0, 1.0).finished(); }
const Mat<1, 2> kS = (Mat<1, 2>() << 1.0, 0.0).finished();

// Linear model f(q) = M q: J is constant and the proxy is held still, so the paper's two
// approximations are exact and eq. 2, 5, 9 must equal d tau / d q by finite differences.
struct LinearModel {
  static constexpr int kJoints = 2, kActuated = 1, kTask = 2;
  Mat2 M = handJ();
  Mat<1, 2> S = kS;
  void forward(const Vec2& q, Vec2& x) const noexcept { x = M * q; }
  void jacobian(const Vec2&, Mat2& J) const noexcept { J = M; }
  const Mat<1, 2>& selection() const noexcept { return S; }
};

// Nonlinear, three task coordinates for two joints: the optimum has a nonzero residual.
struct CurvedModel {
  static constexpr int kJoints = 2, kActuated = 1, kTask = 3;
  Mat<1, 2> S = kS;
  // Element-wise on purpose: with GCC 12.2 at -O3, `x << sin(..), ...` here produced wrong values
  // once inlined into the solver (the same code was right at -O2 and under sanitizers).
  void forward(const Vec2& q, Vec3& x) const noexcept {
    x(0) = std::sin(q(0)) + 0.3 * q(1);
    x(1) = q(1) * q(1) + q(0);
    x(2) = 0.5 * q(0) * q(1);
  }
  void jacobian(const Vec2& q, Mat<3, 2>& J) const noexcept {
    J(0, 0) = std::cos(q(0)), J(0, 1) = 0.3;
    J(1, 0) = 1.0, J(1, 1) = 2.0 * q(1);
    J(2, 0) = 0.5 * q(1), J(2, 1) = 0.5 * q(0);
  }
  const Mat<1, 2>& selection() const noexcept { return S; }
};
}  // namespace

TEST_CASE("core: selection helpers") {
  CHECK(ua::isSelection<1, 2>(kS));
  CHECK_FALSE(ua::isSelection<1, 2>((Mat<1, 2>() << 1.0, 1.0).finished()));
  CHECK_FALSE(ua::isSelection<2, 3>((Mat<2, 3>() << 0, 1, 0, 0, 1, 0).finished()));  // repeated joint
  CHECK(ua::complementSelection<1, 2>(kS) == (Mat<1, 2>() << 0.0, 1.0).finished());
  const Mat<2, 3> S2 = (Mat<2, 3>() << 0, 0, 1, 1, 0, 0).finished();
  CHECK(ua::complementSelection<2, 3>(S2) == (Mat<1, 3>() << 0, 1, 0).finished());
}

TEST_CASE("core: the three renderers against hand-derived closed forms") {
  const Mat2 J = handJ();
  const Mat2 Zx = Vec2(3.0, 5.0).asDiagonal();
  const Vec2 dx(1.0, 2.0);
  const Mat<1, 1> Zq = Mat<1, 1>::Constant(4.0);
  // Standard: J^T Z_x dx = [[2, 0], [1, 1]] (3, 10) = (6, 13); actuated row: 6.
  CHECK(ua::standardForce(J, kS, Zx, dx)(0) == Approx(6.0));
  // Null-space: J_n = (1, 1), P_n = I - J_n J_n^T / 2 = [[.5, -.5], [-.5, .5]], P_n (3, 10) = (-3.5, 3.5),
  // J_a^T (-3.5, 3.5) = 2 (-3.5) = -7.
  const Mat2 P = ua::nullSpaceProjector<2, 2, 1>(J, ua::complementSelection<1, 2>(kS));
  CHECK(P.isApprox((Mat2() << 0.5, -0.5, -0.5, 0.5).finished(), 1e-14));
  CHECK(ua::nullSpaceForce(J, kS, P, Zx, dx)(0) == Approx(-7.0));
  // Linearized subspace: dq = J^-1 dx = (1/2 - 1, 2) = (-0.5, 2); tau_a = 4 (-0.5) = -2.
  const Vec2 dq = ua::linearizedSubspaceStep(J, dx);
  CHECK(dq.isApprox(Vec2(-0.5, 2.0), 1e-14));
  CHECK(ua::subspaceForce(kS, Zq, dq)(0) == Approx(-2.0));
  // Impedances: eq. 2 -(J_a^T Z_x J) = -((6, 0) J) = -(12, 6); eq. 5 -((1, -1) Z_x J) = -(6, -2);
  // eq. 9 -Z_q on the actuated joint.
  const Mat2 K2 = ua::standardImpedance(J, kS, Zx);
  CHECK(K2.isApprox((Mat2() << -12.0, -6.0, 0.0, 0.0).finished(), 1e-14));
  const Mat2 K5 = ua::nullSpaceImpedance(J, kS, P, Zx);
  CHECK(K5.isApprox((Mat2() << -6.0, 2.0, 0.0, 0.0).finished(), 1e-14));
  CHECK(ua::subspaceImpedance(kS, Zq) == (Mat2() << -4.0, 0.0, 0.0, 0.0).finished());
  // Passivity of the actuated block: all three negative here.
  CHECK(ua::isPassive(K2, kS));
  CHECK(ua::isPassive(K5, kS));
}

TEST_CASE("core: with Z_x = k I the null-space method has d tau_a / d q_n = 0 (paper, after eq. 5)") {
  // Any J: a random-looking one, several stiffnesses.
  Mat<3, 3> J;
  J << 1.2, -0.4, 0.7, 0.3, 2.1, -1.1, -0.8, 0.5, 0.9;
  const Mat<1, 3> S = (Mat<1, 3>() << 0, 1, 0).finished();
  const auto Sn = ua::complementSelection<1, 3>(S);
  const Mat3 P = ua::nullSpaceProjector<3, 3, 1>(J, Sn);
  for (double k : {0.1, 1.0, 250.0}) {
    const Mat3 K = ua::nullSpaceImpedance(J, S, P, (k * Mat3::Identity()).eval());
    const Mat<1, 3> row = S * K;  // d tau_a / d q
    // d tau_a / d q_n: the non-actuated columns; zero to round-off relative to the actuated entry.
    CHECK((row * Sn.transpose()).cwiseAbs().maxCoeff() < 1e-12 * std::abs(row(1)));
    CHECK(row(1) < 0.0);
  }
  // And with an anisotropic Z_x it is not zero: the paper's caveat.
  const Mat3 K = ua::nullSpaceImpedance(J, S, P, Vec3(1.0, 10.0, 0.1).asDiagonal().toDenseMatrix());
  CHECK(((S * K) * Sn.transpose()).cwiseAbs().maxCoeff() > 1e-3);
}

TEST_CASE("core: theoretical impedances equal finite differences when J is constant (eq. 2, 5, 9)") {
  const LinearModel m;
  const Mat2 Zx = (Mat2() << 3.0, 0.5, 0.5, 2.0).finished();
  const Mat<1, 1> Zq = Mat<1, 1>::Constant(4.0);
  const Vec2 xp(0.4, -0.2);
  const Mat<1, 2> Sn = ua::complementSelection<1, 2>(kS);
  const Mat2 P = ua::nullSpaceProjector<2, 2, 1>(m.M, Sn);
  auto tau = [&](int method) {
    return [&, method](const Vec2& q) {
      Vec2 x;
      m.forward(q, x);
      const Vec2 dx = xp - x;
      Vec2 t = Vec2::Zero();  // tau = S^T tau_a
      if (method == 0) t = kS.transpose() * ua::standardForce(m.M, kS, Zx, dx);
      if (method == 1) t = kS.transpose() * ua::nullSpaceForce(m.M, kS, P, Zx, dx);
      if (method == 2) t = kS.transpose() * ua::subspaceForce(kS, Zq, ua::linearizedSubspaceStep(m.M, dx));
      return t;
    };
  };
  const Vec2 q(0.3, -0.6);
  CHECK((centralDifferenceJacobian(tau(0), q) - ua::standardImpedance(m.M, kS, Zx)).norm() < 1e-8);
  CHECK((centralDifferenceJacobian(tau(1), q) - ua::nullSpaceImpedance(m.M, kS, P, Zx)).norm() < 1e-8);
  CHECK((centralDifferenceJacobian(tau(2), q) - ua::subspaceImpedance(kS, Zq)).norm() < 1e-8);
  CHECK((ua::linearizedSubspaceImpedance(m.M, kS, Zq) - ua::subspaceImpedance(kS, Zq)).norm() < 1e-14);
}

TEST_CASE("core: finite-difference stiffness and its undefined frames") {
  CHECK(ua::finiteDifferenceStiffness<1>(Vec<1>(-2.0), Vec<1>(0.5), 1e-6) == Approx(-4.0));
  CHECK(std::isnan(ua::finiteDifferenceStiffness<1>(Vec<1>(-2.0), Vec<1>(1e-7), 1e-6)));
  // Two actuators: the stiffness along the motion.
  CHECK(ua::finiteDifferenceStiffness<2>(Vec2(1.0, -3.0), Vec2(0.0, 1.0), 1e-6) == Approx(-3.0));
}

TEST_CASE("core: singular J keeps every renderer finite and bounded") {
  Mat2 J;
  J << 1.0, 2.0, 0.5, 1.0;  // rank 1
  const Vec2 dx(1.0, -1.0);
  RegularizedSolveInfo info;
  const Vec2 dq = ua::linearizedSubspaceStep(J, dx, {}, &info);
  CHECK(dq.allFinite());
  CHECK(info.sigma_min < 1e-12);
  // Damped at the singularity: |dq| <= |dx| / (2 lambda), lambda = 1e-2 s_max.
  CHECK(dq.norm() <= dx.norm() / (2.0 * 1e-2 * info.sigma_max) + 1e-12);
  // J_n = 0: the projector removes nothing rather than dividing by zero.
  Mat2 Jz;
  Jz << 1.0, 0.0, 2.0, 0.0;
  const Mat2 P = ua::nullSpaceProjector<2, 2, 1>(Jz, ua::complementSelection<1, 2>(kS));
  CHECK(P.isApprox(Mat2::Identity()));
}

TEST_CASE("core: nonlinear subspace solve reaches the optimum, GN and LM alike") {
  const CurvedModel m;
  const Vec2 q_true(0.4, -0.3);
  Vec3 x_reachable;
  m.forward(q_true, x_reachable);
  for (auto method : {LeastSquaresMethod::kGaussNewton, LeastSquaresMethod::kLevenbergMarquardt}) {
    SubspaceSolveOptions opt;
    opt.method = method;
    opt.max_iterations = 50;
    // Reachable proxy: q* = q_true, zero residual.
    Vec2 q(0.0, 0.0);
    auto rep = solveSubspaceProxy(m, x_reachable, q, opt);
    CHECK(rep.converged);
    CHECK(rep.fault == Fault::kNone);
    CHECK((q - q_true).norm() < 1e-9);
    CHECK(rep.residual < 1e-9);
  }
  // Unreachable proxy (zero-residual no longer possible): a stationary point of |x_p - f(q)|^2,
  // J^T r = 0. This large-residual case is where LM's damping matters: GN oscillates here (it is
  // allowed to fail, but must then say so), LM converges (linearly, hence the looser tolerance).
  const Vec3 xp(0.9, -0.2, 0.6);
  const auto gradientAt = [&](const Vec2& q) {
    Vec3 x;
    m.forward(q, x);
    Mat<3, 2> J;
    m.jacobian(q, J);
    return (J.transpose() * (xp - x)).norm();
  };
  SubspaceSolveOptions lm;
  lm.method = LeastSquaresMethod::kLevenbergMarquardt;
  lm.tolerance = 1e-6;
  lm.max_iterations = 200;
  Vec2 q(0.0, 0.0);
  auto rep = solveSubspaceProxy(m, xp, q, lm);
  CHECK(rep.converged);
  CHECK(gradientAt(q) < 1e-5);  // |J^T r| < |J|_F * tolerance, |J|_F ~ 2 here
  CHECK(rep.residual > 0.1);
  SubspaceSolveOptions gn;
  gn.max_iterations = 200;
  q.setZero();
  rep = solveSubspaceProxy(m, xp, q, gn);
  WARN("Gauss-Newton on a large-residual problem: converged " << rep.converged << " after " << rep.iterations
                                                             << " iterations, |J^T r| = " << gradientAt(q));
  if (rep.converged) CHECK(gradientAt(q) < 1e-8);
  else CHECK(rep.fault == Fault::kNotConverged);
}

TEST_CASE("core: nonlinear solve reports non-convergence and non-finite input") {
  const CurvedModel m;
  SubspaceSolveOptions opt;
  opt.max_iterations = 1;
  Vec2 q(1.0, 1.0);
  auto rep = solveSubspaceProxy(m, Vec3(0.9, -0.2, 0.6), q, opt);
  CHECK(rep.fault == Fault::kNotConverged);
  CHECK_FALSE(rep.converged);
  CHECK(q.allFinite());
  q << std::numeric_limits<double>::quiet_NaN(), 0.0;
  rep = solveSubspaceProxy(m, Vec3::Zero(), q, opt);
  CHECK(rep.fault == Fault::kNonFiniteInput);
  Vec2 q2(0.0, 0.0);
  rep = solveSubspaceProxy(m, Vec3(std::numeric_limits<double>::infinity(), 0, 0), q2, opt);
  CHECK(rep.fault == Fault::kNonFiniteInput);
  CHECK(q2.isZero());
}

TEST_CASE("core: the nonlinear solve allocates nothing") {
  const CurvedModel m;
  Vec2 q(0.0, 0.0);
  SubspaceSolveOptions lm;
  lm.method = LeastSquaresMethod::kLevenbergMarquardt;
  tools::AllocationScope scope;
  auto rep = solveSubspaceProxy(m, Vec3(0.5, 0.1, 0.2), q, {});
  q.setZero();
  rep = solveSubspaceProxy(m, Vec3(0.5, 0.1, 0.2), q, lm);
  CHECK(scope.count() == 0);
  CHECK(rep.iterations > 0);
}
