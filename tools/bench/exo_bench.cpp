// Finger exoskeleton (paper 000): one servo tick per renderer, and the nonlinear subspace solve at
// several tolerances with the error it leaves (time next to accuracy). Every benchmark reports
// heap allocations per iteration (must be 0).
#include <benchmark/benchmark.h>

#include <cmath>

#include "uhaptics/models/exo_finger_model.hpp"
#include "uhaptics/renderers/underactuated_renderers.hpp"
#include "uhaptics/tools/alloc_probe.hpp"

namespace {
using namespace uhaptics;
using Model = ExoFingerModel;

const Model& model() {
  static const Model m = Model::load(Model::defaultParamsPath(UHAPTICS_PARAMS_DIR));
  return m;
}

UnderactuatedGains<Model> fig4Gains() {
  UnderactuatedGains<Model> g;
  g.Zx = (1.0 / (48.3 * 48.3)) * Mat2::Identity();  // Z_q / avg(|J_a|)^2, Fig. 4 normalization
  g.Zq(0, 0) = 1.0;
  g.force_limit = model().forceLimit();
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

template <class Renderer, class... Extra>
void tickBenchmark(benchmark::State& state, Extra... extra) {
  Renderer renderer(model(), fig4Gains(), extra...);
  const Model::TaskVector proxy = Model::TaskVector::Zero();
  Model::ActuatorVector tau;
  int k = 0;
  const std::uint64_t before = tools::threadAllocationCount();
  for (auto _ : state) {
    const Fault f = renderer.tick(sweep().q[k], proxy, tau);
    benchmark::DoNotOptimize(tau);
    benchmark::DoNotOptimize(f);
    k = (k + 1) % Sweep::kStates;
  }
  state.counters["allocs_per_tick"] = benchmark::Counter(
      static_cast<double>(tools::threadAllocationCount() - before), benchmark::Counter::kAvgIterations);
}

void BM_ExoTickStandard(benchmark::State& s) { tickBenchmark<StandardRenderer<Model>>(s); }
void BM_ExoTickNullSpace(benchmark::State& s) { tickBenchmark<NullSpaceRenderer<Model>>(s); }
void BM_ExoTickSubspaceLinearized(benchmark::State& s) { tickBenchmark<LinearizedSubspaceRenderer<Model>>(s); }
void BM_ExoTickSubspaceNonlinear(benchmark::State& s) {
  tickBenchmark<NonlinearSubspaceRenderer<Model>>(s, SubspaceSolveOptions{});
}
BENCHMARK(BM_ExoTickStandard);
BENCHMARK(BM_ExoTickNullSpace);
BENCHMARK(BM_ExoTickSubspaceLinearized);
BENCHMARK(BM_ExoTickSubspaceNonlinear);

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
  state.counters["allocs_per_tick"] = allocs / solves;
  state.SetLabel(state.range(1) ? "LM" : "GN");
}
BENCHMARK(BM_ExoSubspaceSolveCold)->ArgsProduct({{2, 4, 6, 8, 10, 12}, {0, 1}});

}  // namespace
