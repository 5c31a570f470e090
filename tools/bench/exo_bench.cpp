// Finger exoskeleton (paper 000): one servo tick per renderer, and the nonlinear subspace solve at
// several tolerances with the error it leaves (time next to accuracy). Every benchmark reports
// heap allocations per iteration (must be 0).
#include <benchmark/benchmark.h>

#include <cmath>
#include <vector>

#include "uhaptics/models/exo_finger_model.hpp"
#include "uhaptics/renderers/underactuated_renderers.hpp"
#include "uhaptics/tools/alloc_probe.hpp"

namespace {
using namespace uhaptics;
using Model = ExoFingerModel;

const Model& model() {
  static const Model m = Model::load(std::string(UHAPTICS_PARAMS_DIR) + "/exo_finger.json");
  return m;
}

UnderactuatedGains<Model> fig4Gains() {
  UnderactuatedGains<Model> g;
  g.Zx = (1.0 / (48.3 * 48.3)) * Mat2::Identity();  // Z_q / avg(|J_a|)^2, Fig. 4 normalization
  g.Zq(0, 0) = 1.0;
  g.force_limit = model().effortLimits();
  return g;
}

// A slow flexion sweep sampled at 500 Hz: consecutive ticks see consecutive states, as in service.
struct Sweep {
  static constexpr int kStates = 1000;
  Model::JointVector q[kStates];
  Sweep() {
    for (int k = 0; k < kStates; ++k) {
      const double s = 0.5 * (1.0 - std::cos(2.0 * M_PI * k / kStates));
      Model::TaskVector x(0.05 + 1.4 * s, 0.05 + 1.6 * s);
      model().inverse(x, q[k]);
    }
  }
};
const Sweep& sweep() {
  static const Sweep s;
  return s;
}

// Free space: the proxy sits on the probe (CHAI3D's proxy follows the tool when nothing is touched).
const Model::TaskVector& probe(int k) {
  static const std::vector<Model::TaskVector> x = [] {
    std::vector<Model::TaskVector> out(Sweep::kStates);
    for (int i = 0; i < Sweep::kStates; ++i) model().forward(sweep().q[i], out[i]);
    return out;
  }();
  return x[k];
}

template <class Renderer, class... Extra>
void tickBenchmark(benchmark::State& state, bool in_contact, Extra... extra) {
  Renderer renderer(model(), fig4Gains(), extra...);
  const Model::TaskVector contact_proxy = Model::TaskVector::Zero();
  Model::ActuatorVector tau;
  int k = 0;
  probe(0);  // builds the probe table outside the counted loop
  const std::uint64_t before = tools::threadAllocationCount();
  for (auto _ : state) {
    const Fault f = renderer.tick(sweep().q[k], in_contact ? contact_proxy : probe(k), tau);
    benchmark::DoNotOptimize(tau);
    benchmark::DoNotOptimize(f);
    k = (k + 1) % Sweep::kStates;
  }
  state.counters["allocs_per_tick"] = benchmark::Counter(
      static_cast<double>(tools::threadAllocationCount() - before), benchmark::Counter::kAvgIterations);
}

// range(0): 1 = in contact (proxy held at x = 0, the Fig. 4 protocol), 0 = free space.
void BM_ExoTickStandard(benchmark::State& s) { tickBenchmark<StandardRenderer<Model>>(s, s.range(0) != 0); }
void BM_ExoTickNullSpace(benchmark::State& s) { tickBenchmark<NullSpaceRenderer<Model>>(s, s.range(0) != 0); }
void BM_ExoTickSubspaceLinearized(benchmark::State& s) {
  tickBenchmark<LinearizedSubspaceRenderer<Model>>(s, s.range(0) != 0);
}
void BM_ExoTickSubspaceNonlinear(benchmark::State& s) {
  tickBenchmark<NonlinearSubspaceRenderer<Model>>(s, s.range(0) != 0, SubspaceSolveOptions{});
}
BENCHMARK(BM_ExoTickStandard)->Arg(1)->Arg(0)->ArgName("contact");
BENCHMARK(BM_ExoTickNullSpace)->Arg(1)->Arg(0)->ArgName("contact");
BENCHMARK(BM_ExoTickSubspaceLinearized)->Arg(1)->Arg(0)->ArgName("contact");
BENCHMARK(BM_ExoTickSubspaceNonlinear)->Arg(1)->Arg(0)->ArgName("contact");

// The cold nonlinear solve (no warm start): from a state on the sweep to the Fig. 4 proxy x = 0,
// i.e. up to ~90 deg away, the worst case of a tick after a reset. range(0): -log10(tolerance);
// range(1): 0 = Gauss-Newton, 1 = Levenberg-Marquardt. Counters: iterations, forward evaluations
// and the error left, |f(q*) - x_p| in rad (the true optimum has zero residual here).
void BM_ExoSubspaceSolveCold(benchmark::State& state) {
  SubspaceSolveOptions opt;
  opt.tolerance = std::pow(10.0, -static_cast<double>(state.range(0)));
  opt.max_iterations = 100;
  opt.method = state.range(1) ? LeastSquaresMethod::kLevenbergMarquardt : LeastSquaresMethod::kGaussNewton;
  const Model::TaskVector proxy = Model::TaskVector::Zero();
  double iterations = 0.0, evaluations = 0.0, worst_error = 0.0, solves = 0.0, failures = 0.0;
  int k = 0;
  const std::uint64_t before = tools::threadAllocationCount();
  for (auto _ : state) {
    Model::JointVector q = sweep().q[k];
    const SubspaceSolveReport rep = solveSubspaceProxy(model(), proxy, q, opt);
    benchmark::DoNotOptimize(q);
    iterations += rep.iterations;
    evaluations += rep.evaluations;
    worst_error = std::max(worst_error, rep.residual);
    failures += rep.converged ? 0.0 : 1.0;
    solves += 1.0;
    k = (k + 37) % Sweep::kStates;
  }
  const double allocs = static_cast<double>(tools::threadAllocationCount() - before);
  state.counters["iterations"] = iterations / solves;
  state.counters["evaluations"] = evaluations / solves;
  state.counters["error"] = worst_error;
  state.counters["not_converged"] = failures / solves;
  state.counters["allocs_per_solve"] = allocs / solves;
  const bool is_default =
      std::abs(opt.tolerance / SubspaceSolveOptions{}.tolerance - 1.0) < 1e-9 && state.range(1) == 0;
  state.counters["default"] = is_default ? 1.0 : 0.0;
  state.SetLabel(state.range(1) ? "LM" : "GN");
}
BENCHMARK(BM_ExoSubspaceSolveCold)->ArgsProduct({{2, 4, 6, 8, 10, 12}, {0, 1}});

// Where the proxy is relative to the finger: 0 = Fig. 4 (x_p = 0, up to ~90 deg away: a tick after
// a reset or a jump of the proxy), 1 = near a contact (x_p = f(q) + 5 deg on each joint, where the
// linearization is meant to hold).
Model::TaskVector proxyFor(int k, int where) {
  if (where == 0) return Model::TaskVector::Zero();
  Model::TaskVector x;
  model().forward(sweep().q[k], x);
  return x + Model::TaskVector::Constant(5.0 * M_PI / 180.0);
}

// Nonlinear (eq. 6) against linearized (eq. 7-8) subspace proxy, cold. range(0): Gauss-Newton
// iteration cap (tolerance 0, so every allowed iteration runs; 0 = the linearized proxy, one
// undamped step dq = J^-1 (x_p - f(q)) without backtracking), range(1): proxyFor(). Error: the
// worst |x_p - f(q*)| in rad, i.e. the distance to the exact answer q* = f^-1(x_p) (closed form,
// zero residual), measured in the finger's joint angles. Cost: the solve alone.
void BM_ExoSubspaceIterations(benchmark::State& state) {
  const int cap = static_cast<int>(state.range(0));
  const int where = static_cast<int>(state.range(1));
  SubspaceSolveOptions opt;
  opt.tolerance = 0.0;
  opt.max_iterations = cap;
  Model::TaskVector proxies[Sweep::kStates];
  for (int i = 0; i < Sweep::kStates; ++i) proxies[i] = proxyFor(i, where);
  double worst_error = 0.0;
  int k = 0;
  Model::TaskVector x;
  Model::Jacobian J;
  for (auto _ : state) {
    Model::JointVector q = sweep().q[k];
    if (cap == 0) {
      model().forward(q, x);
      model().jacobian(q, J);
      q += regularizedSolve(J, Model::TaskVector(proxies[k] - x), opt.regularization);
    } else {
      solveSubspaceProxy(model(), proxies[k], q, opt);
    }
    benchmark::DoNotOptimize(q);
    model().forward(q, x);
    worst_error = std::max(worst_error, (proxies[k] - x).norm());
    k = (k + 37) % Sweep::kStates;
  }
  state.counters["error"] = worst_error;
  state.SetLabel(cap == 0 ? "linearized" : "nonlinear GN");
}
BENCHMARK(BM_ExoSubspaceIterations)->ArgsProduct({{0, 1, 2, 3, 4, 5, 6, 8}, {0, 1}})->ArgNames({"iterations", "near"});

// The servo case: warm-started nonlinear ticks along the sweep with the proxy 5 deg ahead of the
// finger, against the default tolerance. Error as above.
void BM_ExoSubspaceWarmTolerance(benchmark::State& state) {
  SubspaceSolveOptions opt;
  opt.tolerance = std::pow(10.0, -static_cast<double>(state.range(0)));
  Model::TaskVector proxies[Sweep::kStates];
  for (int i = 0; i < Sweep::kStates; ++i) proxies[i] = proxyFor(i, 1);
  Model::JointVector q = sweep().q[0];
  solveSubspaceProxy(model(), proxies[0], q, opt);
  double worst_error = 0.0, iterations = 0.0, solves = 0.0;
  int k = 1;
  Model::TaskVector x;
  for (auto _ : state) {
    const SubspaceSolveReport rep = solveSubspaceProxy(model(), proxies[k], q, opt);  // q: last q*
    benchmark::DoNotOptimize(q);
    model().forward(q, x);
    worst_error = std::max(worst_error, (proxies[k] - x).norm());
    iterations += rep.iterations;
    solves += 1.0;
    k = (k + 1) % Sweep::kStates;
  }
  state.counters["error"] = worst_error;
  state.counters["iterations"] = iterations / solves;
  state.counters["default"] = std::abs(opt.tolerance / SubspaceSolveOptions{}.tolerance - 1.0) < 1e-9 ? 1.0 : 0.0;
}
BENCHMARK(BM_ExoSubspaceWarmTolerance)->DenseRange(2, 14, 2)->ArgName("neg_log10_tol");

}  // namespace
