// What the passivity layer costs per servo tick (issue 29: at most 0.2 us).
//
// BM_PassivityLayer: an active joint-space policy (a spring wall plus a negative damper: a few
// multiplies, nearly free) ticked on its own (layer:0) and wrapped in uhaptics::PassivePolicy
// (layer:1), for 1 to 6 actuated joints, over a recorded press into the wall and back. The policy
// keeps giving out energy, so the controller damps on a large share of the ticks (active_share),
// where the layer does the most work. Its cost is the difference of the two rows.
//
// BM_PassiveHapticDevice (with the CHAI3D layer): one application command, getPosition() then
// setForce(), on a CHAI3D device that does nothing but serve the same recorded motion, bare
// (decorator:0) and through chai3d::cPassiveHapticDevice (decorator:1).
#include <benchmark/benchmark.h>

#include <array>
#include <cmath>
#include <memory>
#include <vector>

#include "uhaptics/renderers/passive_policy.hpp"
#include "uhaptics/tools/alloc_probe.hpp"

#ifdef UHAPTICS_BENCH_CHAI3D
#include "uhaptics/chai3d/CPassiveHapticDevice.hpp"
#endif

namespace {

using namespace uhaptics;

constexpr double kPeriod = 1e-3;  // [s]
constexpr int kSamples = 1000;    // one recorded lap

// A lap of the joints pressing 5 mrad into a wall at 0 and back with a sampled oscillation on the
// way, and their backward-difference rates.
struct Lap {
  std::vector<std::array<double, kMaxSensedJoints>> q, qd;
  Lap() : q(kSamples), qd(kSamples) {
    for (int k = 0; k < kSamples; ++k) {
      const double s = 2.0 * M_PI * k / kSamples;
      for (int j = 0; j < kMaxSensedJoints; ++j) q[k][j] = 0.005 * std::sin(s + 0.3 * j) + 0.0005 * std::sin(40.0 * s);
    }
    for (int k = 0; k < kSamples; ++k)
      for (int j = 0; j < kMaxSensedJoints; ++j) qd[k][j] = (q[k][j] - q[(k + kSamples - 1) % kSamples][j]) / kPeriod;
  }
};
const Lap& lap() {
  static const Lap l;
  return l;
}

class ActiveWallPolicy final : public DevicePolicy {
 public:
  explicit ActiveWallPolicy(int actuators) : actuators_(actuators) {}
  std::string name() const override { return "active wall"; }
  void reset(int) override {}
  void sense(const SensedJoints& reading, SensedState&) noexcept override {
    q_ = reading.positions;
    qd_ = reading.rates;
  }
  Fault render(const SceneInput&, double* efforts) noexcept override {
    for (int i = 0; i < actuators_; ++i) efforts[i] = (q_[i] > 0.0 ? -30.0 * q_[i] : 0.0) + 0.05 * qd_[i];
    return Fault::kNone;
  }

 private:
  int actuators_;
  const double* q_ = nullptr;
  const double* qd_ = nullptr;
};

void BM_PassivityLayer(benchmark::State& state) {
  const int actuators = static_cast<int>(state.range(0));
  const bool layer = state.range(1) != 0;
  std::unique_ptr<DevicePolicy> policy = std::make_unique<ActiveWallPolicy>(actuators);
  PassivePolicy* passive = nullptr;
  if (layer) {
    PassivePolicy::Options options;
    options.actuators = actuators;
    options.controller.max_damping = 0.5;
    options.controller.effort_limit = Eigen::VectorXd::Constant(actuators, 2.0);
    auto wrapped = std::make_unique<PassivePolicy>(std::move(policy), options, FigureRecorder::none());
    passive = wrapped.get();
    policy = std::move(wrapped);
  }
  policy->reset(0);
  SensedState sensed;
  SceneInput input;
  input.dt = kPeriod;
  std::array<double, kMaxSensedJoints> efforts{};
  int k = 0;
  const std::uint64_t before = tools::threadAllocationCount();
  for (auto _ : state) {
    policy->sense(SensedJoints{lap().q[k].data(), lap().qd[k].data(), false}, sensed);
    const Fault f = policy->render(input, efforts.data());
    benchmark::DoNotOptimize(efforts.data());
    benchmark::DoNotOptimize(f);
    k = (k + 1) % kSamples;
  }
  state.counters["allocs_per_tick"] = benchmark::Counter(
      static_cast<double>(tools::threadAllocationCount() - before), benchmark::Counter::kAvgIterations);
  if (passive) {
    state.counters["active_share"] = benchmark::Counter(static_cast<double>(passive->controller().activeTicks()),
                                                        benchmark::Counter::kAvgIterations);
  }
}
BENCHMARK(BM_PassivityLayer)->ArgsProduct({{1, 2, 4, 6}, {0, 1}})->ArgNames({"actuators", "layer"});

#ifdef UHAPTICS_BENCH_CHAI3D

// Serves the recorded lap on x, one sample per command, and takes commands without doing anything.
class cReplayDevice : public chai3d::cGenericHapticDevice {
 public:
  cReplayDevice() {
    m_specifications.m_maxLinearDamping = 20.0;
    m_specifications.m_sensedRotation = true;
    m_specifications.m_maxAngularDamping = 0.05;
    m_deviceAvailable = true;
  }
  bool open() override { return m_deviceReady = true; }
  bool close() override { return !(m_deviceReady = false); }
  bool getPosition(chai3d::cVector3d& a_position) override {
    a_position.set(lap().q[m_k][0], lap().q[m_k][1], lap().q[m_k][2]);
    return true;
  }
  bool getLinearVelocity(chai3d::cVector3d& a_velocity) override {
    a_velocity.set(lap().qd[m_k][0], lap().qd[m_k][1], lap().qd[m_k][2]);
    return true;
  }
  bool getRotation(chai3d::cMatrix3d& a_rotation) override {
    a_rotation.identity();
    a_rotation.rotateAboutGlobalAxisRad(chai3d::cVector3d(0, 0, 1), lap().q[m_k][3]);
    return true;
  }
  bool getAngularVelocity(chai3d::cVector3d& a_velocity) override {
    a_velocity.set(0.0, 0.0, lap().qd[m_k][3]);
    return true;
  }
  bool setForceAndTorqueAndGripperForce(const chai3d::cVector3d& a_force, const chai3d::cVector3d& a_torque,
                                        double) override {
    benchmark::DoNotOptimize(a_force(0) + a_torque(2));
    m_k = (m_k + 1) % kSamples;
    return true;
  }

 private:
  int m_k = 0;
};

void BM_PassiveHapticDevice(benchmark::State& state) {
  auto replay = std::make_shared<cReplayDevice>();
  chai3d::cGenericHapticDevicePtr device = replay;
  if (state.range(0) != 0) {
    auto passive = chai3d::cPassiveHapticDevice::create(replay);
    passive->setServoPeriod(kPeriod);
    device = passive;
  }
  device->open();
  chai3d::cVector3d position;
  chai3d::cMatrix3d rotation;
  const std::uint64_t before = tools::threadAllocationCount();
  for (auto _ : state) {
    device->getPosition(position);
    device->getRotation(rotation);
    const chai3d::cVector3d force(position(0) > 0.0 ? -2000.0 * position(0) : 0.0, 0.0, 0.0);
    device->setForceAndTorqueAndGripperForce(force, chai3d::cVector3d(0.0, 0.0, -0.5 * position(1)), 0.0);
  }
  state.counters["allocs_per_tick"] = benchmark::Counter(
      static_cast<double>(tools::threadAllocationCount() - before), benchmark::Counter::kAvgIterations);
}
BENCHMARK(BM_PassiveHapticDevice)->Arg(0)->Arg(1)->ArgName("decorator");

#endif  // UHAPTICS_BENCH_CHAI3D

}  // namespace
