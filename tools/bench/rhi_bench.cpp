// Paper 003 controller tick on the 4-DoF RHI: analytic vs finite-difference cost gradient (run time
// next to gradient error) and the free-motion fast path against a contact tick.
#include <benchmark/benchmark.h>

#include <cmath>

#include "uhaptics/core/fme_cost.hpp"
#include "uhaptics/models/planar_linkage_model.hpp"
#include "uhaptics/renderers/fme_null_space_controller.hpp"
#include "uhaptics/tools/alloc_probe.hpp"

namespace {
using namespace uhaptics;
using Controller = FmeNullSpaceController<Rhi4Model>;

const Rhi4Model& model() {
  static const Rhi4Model m = Rhi4Model::load(std::string(UHAPTICS_PARAMS_DIR) + "/rhi4.json", "rhi4");
  return m;
}

const Vec<4> kQ(1.15, 0.05, 0.0, 1.5);  // near the free-ellipsoid configuration at X0 = [0.5, 0.1]
const Vec<4> kQd(0.05, -0.02, 0.1, 0.0);

// Reference gradient: fourth-order (5-point) central differences of nu at steps h and h/2,
// Richardson-extrapolated (error O(h^6) ~ 1e-17 at h = 2e-3, rounding ~ eps |nu| / h ~ 1e-13): an
// independent route (values of nu only) that is tighter than both methods it judges.
Vec<4> referenceGradient(const Mat2& Mdes) {
  const Vec<4> w2 = fme::inverseSquaredLimits(model().effortLimits());
  const auto fivePoint = [&](int k, double h) {
    double v[4];
    const double steps[4] = {-2 * h, -h, h, 2 * h};
    for (int s = 0; s < 4; ++s) {
      Vec<4> q = kQ;
      q(k) += steps[s];
      fme::fmeCostValue(model(), q, w2, Mdes, v[s]);
    }
    return (v[0] - 8 * v[1] + 8 * v[2] - v[3]) / (12 * h);
  };
  Vec<4> g;
  for (int k = 0; k < 4; ++k) g(k) = (16.0 * fivePoint(k, 1e-3) - fivePoint(k, 2e-3)) / 15.0;
  return g;
}

void tickBenchmark(benchmark::State& state, fme::GradientMethod method, const Vec2& force) {
  Controller::Options o;
  o.gradient = method;
  Controller c(model(), model().effortLimits(), model().homeJoints(), o);
  Vec<4> tau;
  double t = 0.0;
  tools::AllocationScope scope;
  for (auto _ : state) {
    c.tick(t, kQ, kQd, force, tau);
    t += 1e-3;
    benchmark::DoNotOptimize(tau.data());
  }
  state.counters["allocs_per_tick"] =
      benchmark::Counter(static_cast<double>(scope.count()) / static_cast<double>(state.iterations()));
  // Gradient error against the 5-point reference, relative to its norm.
  const Vec<4> w2 = fme::inverseSquaredLimits(model().effortLimits());
  Mat<2, 4> J;
  model().jacobian(kQ, J);
  double nu = 0.0;
  Vec<4> g;
  fme::fmeCostGradient(model(), kQ, J, w2, c.desiredEllipsoid(), method, nu, g);
  const Vec<4> ref = referenceGradient(c.desiredEllipsoid());
  state.counters["error"] = (g - ref).norm() / ref.norm();
  state.counters["skipped"] = c.status().skipped_contact_work ? 1.0 : 0.0;
}

void BM_RhiTickAnalyticGradient(benchmark::State& s) {
  tickBenchmark(s, fme::GradientMethod::kAnalytic, Vec2(0.0, -2.0));
}
void BM_RhiTickFiniteDifferenceGradient(benchmark::State& s) {
  tickBenchmark(s, fme::GradientMethod::kFiniteDifference, Vec2(0.0, -2.0));
}
void BM_RhiTickFreeMotion(benchmark::State& s) { tickBenchmark(s, fme::GradientMethod::kAnalytic, Vec2::Zero()); }

// The gradient alone (no projection, no observer), both ways; finite differences at the relative
// step 10^-range(0) (6e-6, centralDifferenceStep's default, is the library's choice).
void gradientBenchmark(benchmark::State& state, fme::GradientMethod method, double fd_step = 6.0e-6) {
  const Vec<4> w2 = fme::inverseSquaredLimits(model().effortLimits());
  Mat2 Mdes;
  fme::axisAlignedEllipsoid(Vec2(0.0, 1.0), 3.3, 123.0, Mdes);
  Mat<2, 4> J;
  model().jacobian(kQ, J);
  double nu = 0.0;
  Vec<4> g;
  for (auto _ : state) {
    fme::fmeCostGradient(model(), kQ, J, w2, Mdes, method, nu, g, 1e-8, fd_step);
    benchmark::DoNotOptimize(g.data());
  }
  const Vec<4> ref = referenceGradient(Mdes);
  state.counters["error"] = (g - ref).norm() / ref.norm();
  state.counters["default"] = method == fme::GradientMethod::kAnalytic ? 1.0 : 0.0;  // the controller's default
}
void BM_RhiGradientAnalytic(benchmark::State& s) { gradientBenchmark(s, fme::GradientMethod::kAnalytic); }
void BM_RhiGradientFiniteDifference(benchmark::State& s) {
  gradientBenchmark(s, fme::GradientMethod::kFiniteDifference);
}
void BM_RhiGradientFiniteDifferenceStep(benchmark::State& s) {
  gradientBenchmark(s, fme::GradientMethod::kFiniteDifference, std::pow(10.0, -static_cast<double>(s.range(0))));
}
}  // namespace

BENCHMARK(BM_RhiTickAnalyticGradient);
BENCHMARK(BM_RhiTickFiniteDifferenceGradient);
BENCHMARK(BM_RhiTickFreeMotion);
BENCHMARK(BM_RhiGradientAnalytic);
BENCHMARK(BM_RhiGradientFiniteDifference);
BENCHMARK(BM_RhiGradientFiniteDifferenceStep)->DenseRange(2, 10, 1)->ArgName("neg_log10_step");
