// TAU servo-rate costs: LQR wall tick with and without forward kinematics, free-space tick, spring
// wall tick, one simulated servo period, and the study's throughput (simulated s per wall s).
#include <benchmark/benchmark.h>

#include "device_servo_renderers.hpp"
#include "uhaptics/backends/board_catalog.hpp"
#include "uhaptics/backends/simulated_tau.hpp"
#include "uhaptics/experiments/tau_study.hpp"
#include "uhaptics/renderers/lqr_wall_renderer.hpp"
#include "uhaptics/renderers/spring_wall_renderer.hpp"
#include "uhaptics/renderers/tau_wall_design.hpp"
#include "uhaptics/tools/alloc_probe.hpp"

using namespace uhaptics;

namespace {
const TauModel& tauModel() {
  static const TauModel m = TauModel::load(std::string(UHAPTICS_PARAMS_DIR) + "/tau.json");
  return m;
}
const LqrWallGains& tauGains() {
  static const LqrWallGains g = designLqrWall(tauModel(), tauModel().homePose()).gains;
  return g;
}
// Joint readings around the contact pose, as a pressed tool produces them.
Vec6 jitter(const Vec6& q, int k) { return q + Vec6::Constant(tauModel().encoderResolution() * ((k % 3) - 1)); }

template <typename Renderer>
void runTicks(benchmark::State& state, Renderer& r, bool active, bool give_pose) {
  TauData device(tauModel());
  SurfaceContact c;
  c.active = active;
  c.normal = Vec3::UnitZ();
  c.point = Vec3(0, 0, 0.001);  // wall 1 mm above the tool: in contact
  const Vec6 q0 = tauModel().homeJoints();
  int k = 0;
  tools::AllocationScope scope;
  for (auto _ : state) {
    const Vec6 q = jitter(q0, k++);
    if (give_pose) tauModel().forward(q, device);  // done by the device adapter, outside the tick
    benchmark::DoNotOptimize(r.tick(q, c, give_pose ? &device.pose : nullptr).torque.data());
  }
  state.counters["allocs_per_tick"] = benchmark::Counter(static_cast<double>(scope.count()), benchmark::Counter::kAvgIterations);
}
}  // namespace

static void BM_LqrWallTick_WithForwardKinematics(benchmark::State& state) {
  LqrWallRenderer r(tauModel(), tauGains());
  runTicks(state, r, true, false);
}
BENCHMARK(BM_LqrWallTick_WithForwardKinematics);

static void BM_LqrWallTick_PoseGiven(benchmark::State& state) {
  LqrWallRenderer r(tauModel(), tauGains());
  // Only the tick is timed: the pose is computed outside by pausing the timer would distort a
  // sub-microsecond loop, so this variant reuses one pose (Newton then returns at iteration 0).
  TauData device(tauModel());
  tauModel().forward(tauModel().homeJoints(), device);
  SurfaceContact c;
  c.active = true;
  c.point = Vec3(0, 0, 0.001);
  tools::AllocationScope scope;
  for (auto _ : state) benchmark::DoNotOptimize(r.tick(tauModel().homeJoints(), c, &device.pose).torque.data());
  state.counters["allocs_per_tick"] = benchmark::Counter(static_cast<double>(scope.count()), benchmark::Counter::kAvgIterations);
}
BENCHMARK(BM_LqrWallTick_PoseGiven);

static void BM_LqrWallTick_FreeSpace(benchmark::State& state) {
  LqrWallRenderer r(tauModel(), tauGains());
  runTicks(state, r, false, false);
}
BENCHMARK(BM_LqrWallTick_FreeSpace);

static void BM_SpringWallTick(benchmark::State& state) {
  SpringWallRenderer r(tauModel());
  runTicks(state, r, true, false);
}
BENCHMARK(BM_SpringWallTick);

static void BM_SpringWallTick_FreeSpace(benchmark::State& state) {
  SpringWallRenderer r(tauModel());
  runTicks(state, r, false, false);
}
BENCHMARK(BM_SpringWallTick_FreeSpace);

static void BM_SimulatedTauServoPeriod(benchmark::State& state) {
  SimulatedTau sim(tauModel(), SimulatedTauOptions{});
  TauData d(tauModel());
  tauModel().forward(sim.q(), d);
  tauModel().computeGravity(sim.q(), d);
  tools::AllocationScope scope;
  for (auto _ : state) benchmark::DoNotOptimize(sim.step(d.gravity, Vec3(0, 0, -0.01)));
  state.counters["allocs_per_step"] = benchmark::Counter(static_cast<double>(scope.count()), benchmark::Counter::kAvgIterations);
}
BENCHMARK(BM_SimulatedTauServoPeriod);

// range(1): 1 = the study's plant (linearization held within RunSpec's relinearize_tolerance),
// 0 = the plant solved every period.
static void BM_TauStudyRun(benchmark::State& state) {
  study::RunSpec spec;
  spec.controller = state.range(0) ? study::Controller::kLqr : study::Controller::kSpring;
  if (state.range(1) == 0) spec.relinearize_tolerance = 0.0;
  const DeviceDefinition& tau = *findDeviceByPaper("001");
  const study::TauProduct product{[&tau] { return makeDevicePolicy(tau, UHAPTICS_PARAMS_DIR); },
                                  boardSpec(tau, UHAPTICS_PARAMS_DIR)};
  study::StudyDevice device(product, study::studyWallDesign({}, study::StudyParameters{}.contact_band), 0);
  for (auto _ : state) benchmark::DoNotOptimize(study::simulateRun(tauModel(), device, spec).k_zs);
  state.counters["sim_s_per_s"] = benchmark::Counter(3.0 * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_TauStudyRun)->ArgsProduct({{1, 0}, {1, 0}})->ArgNames({"lqr", "held"})->Unit(benchmark::kMillisecond);
