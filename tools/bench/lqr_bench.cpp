// LQR synthesis speed: DARE (SDA) time and residual against problem size, the plain Riccati
// recursion it replaces, and the full TAU redesign (linearize + augment + ZOH + DARE + gain).
#include <benchmark/benchmark.h>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <random>

#include "uhaptics/core/dare.hpp"
#include "uhaptics/core/lqr_design.hpp"
#include "uhaptics/renderers/tau_wall_design.hpp"

using namespace uhaptics;

namespace {
// n/3 joints, each a discrete double integrator plus an integral state (the TAU structure),
// randomly coupled through B; Q = diag(1, 1e3, 1e7) per joint as in paper 001.
void integratorPlant(int joints, MatX& A, MatX& B, MatX& Q) {
  const double T = 1e-3;
  const int n = 3 * joints;
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  MatX Minv = MatX::Identity(joints, joints) * 30.0;
  for (int i = 0; i < joints; ++i)
    for (int j = 0; j < joints; ++j) Minv(i, j) += 5.0 * u(rng);
  Minv = 0.5 * (Minv + Minv.transpose()).eval();
  StateSpace c;
  c.A = MatX::Zero(2 * joints, 2 * joints);
  c.A.bottomLeftCorner(joints, joints).setIdentity();
  c.B = MatX::Zero(2 * joints, joints);
  c.B.topRows(joints) = Minv;
  MatX C = MatX::Zero(joints, 2 * joints);
  C.rightCols(joints).setIdentity();
  const StateSpace d = discretizeZoh(augmentWithIntegrators(c, C), T);
  A = d.A;
  B = d.B;
  VecX q(n);
  q << VecX::Constant(joints, 1.0), VecX::Constant(joints, 1e3), VecX::Constant(joints, 1e7);
  Q = q.asDiagonal();
}
}  // namespace

static void BM_DareSda(benchmark::State& state) {
  MatX A, B, Q;
  integratorPlant(static_cast<int>(state.range(0)), A, B, Q);
  const MatX R = MatX::Identity(B.cols(), B.cols());
  DareOptions opt;
  opt.check_preconditions = state.range(1) != 0;
  DareResult r;
  for (auto _ : state) {
    r = solveDare(A, B, Q, R, opt);
    benchmark::DoNotOptimize(r.P.data());
  }
  state.counters["states"] = static_cast<double>(A.rows());
  state.counters["residual"] = r.relative_residual;
  state.counters["doublings"] = r.iterations;
}
BENCHMARK(BM_DareSda)->ArgsProduct({{1, 2, 4, 6, 10, 20}, {0, 1}})->ArgNames({"joints", "checks"})
    ->Unit(benchmark::kMicrosecond);

// The textbook alternative: P <- A'PA - A'PB (R + B'PB)^-1 B'PA + Q until it stops changing.
// Linear convergence at rate ~ rho(A - BK)^2: with integrators at z = 1 it needs many steps.
static void BM_DareRiccatiRecursion(benchmark::State& state) {
  MatX A, B, Q;
  integratorPlant(6, A, B, Q);
  const MatX R = MatX::Identity(B.cols(), B.cols());
  int iterations = 0;
  MatX P;
  for (auto _ : state) {
    P = Q;
    for (iterations = 0; iterations < 2000000; ++iterations) {
      const MatX BtP = B.transpose() * P;
      const MatX next = A.transpose() * P * A - (BtP * A).transpose() * (R + BtP * B).ldlt().solve(BtP * A) + Q;
      const double change = (next - P).norm();
      P = next;
      if (change <= 1e-13 * P.norm()) break;
    }
  }
  state.counters["iterations"] = iterations;
  state.counters["residual"] = dareRelativeResidual(A, B, Q, R, P);
}
BENCHMARK(BM_DareRiccatiRecursion)->Iterations(1)->Unit(benchmark::kMillisecond);

// Per-contact redesign (what must fit in one 1 ms servo period): linearize + augment + ZOH + DARE
// (residual and closed-loop checks on) + gain; the observer is kept from the initial design.
static void BM_TauRedesign(benchmark::State& state) {
  static const TauModel model = TauModel::load(std::string(UHAPTICS_PARAMS_DIR) + "/tau.json");
  static const LqrWallDesign designed = designLqrWall(model, model.homePose());
  Vec6 pose = model.homePose();
  pose(0) = 0.01;
  pose(1) = -0.01;
  for (auto _ : state) {
    const LqrWallDesign g = redesignLqrWallGains(model, pose, designed);
    benchmark::DoNotOptimize(g.gains.Kc.data());
  }
}
BENCHMARK(BM_TauRedesign)->Unit(benchmark::kMicrosecond);

// The full design (adds the Hautus checks and the observer's DARE): set-up time, not per contact.
static void BM_TauFullDesign(benchmark::State& state) {
  static const TauModel model = TauModel::load(std::string(UHAPTICS_PARAMS_DIR) + "/tau.json");
  for (auto _ : state) {
    const LqrWallDesign g = designLqrWall(model, model.homePose());
    benchmark::DoNotOptimize(g.gains.Kc.data());
  }
}
BENCHMARK(BM_TauFullDesign)->Unit(benchmark::kMicrosecond);
