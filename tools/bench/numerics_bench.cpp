// Run time against error for the numerical knobs behind the TAU's servo tick and its redesign:
// the forward-kinematics tolerance, the DARE doubling tolerance and the matrix exponential of the
// ZOH. Each benchmark reports `error` (against a reference computed far tighter, by another route
// where one exists) next to its time, so tools/plots/bench_summary.py draws one curve per family.
#include <benchmark/benchmark.h>

#include <Eigen/LU>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <unsupported/Eigen/MatrixFunctions>
#include <vector>

#include "uhaptics/core/dare.hpp"
#include "uhaptics/core/lqr_design.hpp"
#include "uhaptics/models/param_file.hpp"
#include "uhaptics/models/tau_model.hpp"
#include "uhaptics/renderers/tau_wall_design.hpp"

namespace {
using namespace uhaptics;

std::string tauParamsPath() { return std::string(UHAPTICS_PARAMS_DIR) + "/tau.json"; }

// tau.json with another forward-kinematics tolerance (the file's value, 1e-12 m, is the default).
TauModel tauWithFkTolerance(double tolerance) {
  std::ifstream in(tauParamsPath());
  nlohmann::json j = nlohmann::json::parse(in);
  j.at("forward_kinematics").at("tolerance").at("value") = tolerance;
  return TauModel::fromParams(ParamFile::parse(j.dump(), tauParamsPath()));
}

// Servo-rate forward kinematics along a closed path through the workspace (0.8 of the cube's
// half side, half the angle range), 2000 samples per lap: ~0.1 mm per tick, a fast hand at 1 kHz.
// Each solve is warm-started from the previous pose, as in service. Error: max |pose - exact|
// (m and rad), where the exact pose is the one the closed-form inverse produced the joints from.
void BM_TauFkTolerance(benchmark::State& state) {
  const double tolerance = std::pow(10.0, -static_cast<double>(state.range(0)));
  const TauModel m = tauWithFkTolerance(tolerance);
  constexpr int kPoses = 2000;
  std::vector<Vec6> poses(kPoses), joints(kPoses);
  for (int k = 0; k < kPoses; ++k) {
    const double s = 2.0 * M_PI * k / kPoses;
    poses[k] = m.homePose();
    poses[k].head<3>() += 0.8 * m.workspaceHalfSide() * Vec3(std::cos(s), std::sin(2 * s), std::sin(s));
    poses[k].tail<3>() += 0.5 * m.workspaceHalfAngle() * Vec3(std::sin(s), std::cos(s), std::sin(3 * s));
    if (m.inverse(poses[k], joints[k]) != Fault::kNone) {
      state.SkipWithError("pose unreachable");
      return;
    }
  }
  TauData data(m);
  data.pose = poses[0];
  int k = 0;
  double error = 0.0, iterations = 0.0, solves = 0.0;
  for (auto _ : state) {
    const Fault f = m.forward(joints[k], data);
    benchmark::DoNotOptimize(data.pose.data());
    if (f != Fault::kNone) {
      state.SkipWithError("forward kinematics failed");
      return;
    }
    error = std::max(error, (data.pose - poses[k]).cwiseAbs().maxCoeff());
    iterations += data.fk_iterations;
    solves += 1.0;
    k = (k + 1) % kPoses;
  }
  state.counters["error"] = error;
  state.counters["iterations"] = iterations / solves;
  state.counters["tolerance"] = tolerance;
  const double shipped = TauModel::load(tauParamsPath()).fkTolerance();
  state.counters["default"] = std::abs(tolerance / shipped - 1.0) < 1e-9 ? 1.0 : 0.0;
}
BENCHMARK(BM_TauFkTolerance)->DenseRange(6, 15, 1)->ArgName("neg_log10_tol");

// The TAU wall's LQR plant as designLqrWall builds it: linearized at the home pose holding gravity,
// augmented with 6 integrators (18 states, 6 inputs), default weights (README, TAU section).
struct TauPlant {
  StateSpace augmented;  // continuous
  MatX A, B, Q, R;       // discrete (ZOH at the servo period)
  double period = 0.0;
  TauPlant() {
    const TauModel m = TauModel::load(tauParamsPath());
    TauData data(m);
    const Vec6 q0 = m.homeJoints();
    data.pose = m.homePose();
    if (m.forward(q0, data) != Fault::kNone) throw Error("numerics_bench: forward kinematics fails at home");
    m.computeGravity(q0, data);
    const DynamicsFunction f = [&m, &data](const VecX& x, const VecX& u, VecX& xdot) {
      Vec<12> xd;
      if (m.stateDerivative(x, u, data, xd) != Fault::kNone) xd.setConstant(std::nan(""));
      xdot = xd;
    };
    VecX x0 = VecX::Zero(12);
    x0.tail(6) = q0;
    MatX C = MatX::Zero(6, 12);
    C.rightCols(6).setIdentity();
    augmented = augmentWithIntegrators(linearize(f, x0, data.gravity), C);
    period = m.servoPeriod();
    const StateSpace d = discretizeZoh(augmented, period);
    A = d.A;
    B = d.B;
    const LqrWallWeights w;
    VecX qd(18);
    qd << VecX::Constant(6, w.velocity), VecX::Constant(6, w.position), VecX::Constant(6, w.integral);
    Q = qd.asDiagonal();
    R = MatX::Identity(6, 6) * w.torque;
  }
};
const TauPlant& tauPlant() {
  static const TauPlant p;
  return p;
}

// Reference P: the Riccati recursion (value iteration, an independent algorithm) started from the
// SDA solution and run until it stops changing: a fixed point of the recursion is the DARE's
// solution, and starting next to it makes its linear convergence short.
const MatX& dareReference() {
  static const MatX P = [] {
    const TauPlant& p = tauPlant();
    DareOptions o;
    o.tolerance = 1e-15;
    o.max_iterations = 200;
    o.max_relative_residual = 1.0;  // the recursion below is what makes it tight
    MatX X = solveDare(p.A, p.B, p.Q, p.R, o).P;
    for (int k = 0; k < 100000; ++k) {
      const MatX BtX = p.B.transpose() * X;
      const MatX next = p.A.transpose() * X * p.A -
                        (BtX * p.A).transpose() * (p.R + BtX * p.B).ldlt().solve(BtX * p.A) + p.Q;
      const double change = (next - X).norm();
      X = 0.5 * (next + next.transpose());
      if (change <= 1e-15 * X.norm()) break;
    }
    return X;
  }();
  return P;
}

// DARE doubling tolerance: SDA stops when P changes by less than `tolerance` (relative) between
// doublings; default 1e-13. Error: |P - P_ref|_F / |P_ref|_F. The residual check is relaxed so a
// loose tolerance returns its answer instead of throwing; preconditions off (their cost does not
// depend on the tolerance; BM_DareSda times them).
void BM_DareTolerance(benchmark::State& state) {
  const TauPlant& p = tauPlant();
  const MatX& reference = dareReference();
  DareOptions opt;
  opt.tolerance = std::pow(10.0, -static_cast<double>(state.range(0)));
  opt.max_relative_residual = 1.0;
  opt.check_preconditions = false;
  DareResult r;
  try {
    for (auto _ : state) {
      r = solveDare(p.A, p.B, p.Q, p.R, opt);
      benchmark::DoNotOptimize(r.P.data());
    }
  } catch (const Error& e) {
    state.SkipWithError(e.what());
    return;
  }
  state.counters["error"] = (r.P - reference).norm() / reference.norm();
  state.counters["doublings"] = r.iterations;
  state.counters["residual"] = r.relative_residual;
  state.counters["tolerance"] = opt.tolerance;
  state.counters["default"] = std::abs(opt.tolerance / DareOptions{}.tolerance - 1.0) < 1e-9 ? 1.0 : 0.0;
}
BENCHMARK(BM_DareTolerance)->DenseRange(1, 15, 2)->ArgName("neg_log10_tol")->Unit(benchmark::kMicrosecond);

// The ZOH's block matrix (Van Loan) for the TAU plant: [[A, B, Bref], 0] * T.
MatX zohBlock() {
  const StateSpace& c = tauPlant().augmented;
  const double T = tauPlant().period;
  const Eigen::Index n = c.A.rows(), m = c.B.cols(), r = c.Bref.cols();
  MatX block = MatX::Zero(n + m + r, n + m + r);
  block.topLeftCorner(n, n) = c.A * T;
  block.block(0, n, n, m) = c.B * T;
  block.block(0, n + m, n, r) = c.Bref * T;
  return block;
}

double oneNorm(const MatX& A) { return A.cwiseAbs().colwise().sum().maxCoeff(); }

// Scaling and squaring with a Taylor series of the given order: scale to |X|_1 <= theta, sum,
// square back. The simplest member of the family Eigen's default (Pade 13) belongs to.
MatX expTaylor(const MatX& A, int order, double theta) {
  const double norm = oneNorm(A);
  const int s = norm > theta ? static_cast<int>(std::ceil(std::log2(norm / theta))) : 0;
  const MatX X = A / std::ldexp(1.0, s);
  MatX term = MatX::Identity(A.rows(), A.cols()), sum = term;
  for (int k = 1; k <= order; ++k) {
    term = (term * X) / static_cast<double>(k);
    sum += term;
  }
  for (int i = 0; i < s; ++i) sum = (sum * sum).eval();
  return sum;
}

// Reference: Taylor order 30 after scaling to |X|_1 <= 1/64 (truncation ~1e-90: only rounding left),
// an evaluation independent of Eigen's Pade approximant.
const MatX& expReference() {
  static const MatX ref = expTaylor(zohBlock(), 30, 1.0 / 64.0);
  return ref;
}

void BM_ZohExpTaylor(benchmark::State& state) {
  const MatX A = zohBlock();
  MatX E;
  for (auto _ : state) {
    E = expTaylor(A, static_cast<int>(state.range(0)), 0.5);
    benchmark::DoNotOptimize(E.data());
  }
  state.counters["error"] = (E - expReference()).norm() / expReference().norm();
  state.counters["order"] = static_cast<double>(state.range(0));
}
BENCHMARK(BM_ZohExpTaylor)->Arg(2)->Arg(4)->Arg(6)->Arg(8)->Arg(10)->Arg(12)->Arg(16)->ArgName("order")
    ->Unit(benchmark::kMicrosecond);

// The default: Eigen's MatrixExponential (Pade 13 with scaling and squaring), what discretizeZoh calls.
void BM_ZohExpPade13(benchmark::State& state) {
  const MatX A = zohBlock();
  MatX E;
  for (auto _ : state) {
    E = A.exp();
    benchmark::DoNotOptimize(E.data());
  }
  state.counters["error"] = (E - expReference()).norm() / expReference().norm();
  state.counters["block_norm1"] = oneNorm(A);
  state.counters["default"] = 1.0;
}
BENCHMARK(BM_ZohExpPade13)->Unit(benchmark::kMicrosecond);
}  // namespace
