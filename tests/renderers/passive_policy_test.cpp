// The passivity layer in the servo path (uhaptics::PassivePolicy) around a joint-space policy: bit for
// bit when it only observes, an active sampled wall made passive, a million ticks of hostile input,
// the observation chain across periods it did not command, and no allocation per tick.
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <iterator>
#include <limits>
#include <map>
#include <memory>
#include <random>
#include <string>

#include "uhaptics/renderers/passive_policy.hpp"
#include "uhaptics/tools/alloc_probe.hpp"

using namespace uhaptics;

namespace {

constexpr double kT = 1e-3;  // servo period [s]

// A joint-space wall on joint 0 at q = 0 (efforts -K q0 inside it); the other actuators get
// `others`. It can be told to return a fault or a non-finite effort.
class JointWallPolicy final : public DevicePolicy {
 public:
  JointWallPolicy(int actuators, double stiffness) : actuators_(actuators), stiffness_(stiffness) {}
  std::string name() const override { return "joint wall"; }
  void reset(int) override { ++resets; }
  void sense(const SensedJoints& reading, SensedState& state) noexcept override {
    q0_ = reading.positions[0];
    state.position = Vec3(reading.positions[0], 0.0, 0.0);
    state.joints = Eigen::Map<const Eigen::VectorXd>(reading.positions, actuators_ + 1);
  }
  Fault render(const SceneInput&, double* efforts) noexcept override {
    efforts[0] = q0_ > 0.0 ? -stiffness_ * q0_ : 0.0;
    for (int i = 1; i < actuators_; ++i) efforts[i] = others;
    if (override_effort) efforts[0] = *override_effort;
    return fault;
  }
  void readingLost() noexcept override { ++lost; }

  Fault fault = Fault::kNone;
  double others = 0.0;
  const double* override_effort = nullptr;
  int resets = 0, lost = 0;

 private:
  int actuators_;
  double stiffness_;
  double q0_ = 0.0;
};

// A recorder that keeps every figure by name.
class RecordingFigures final : public FigureRecorder {
 public:
  int declareFigure(const char* name, FigureKind kind) override {
    names_[count_] = name;
    kinds_[count_] = kind;
    return count_++;
  }
  void count(int id, std::uint64_t n) noexcept override { values_[id] += static_cast<double>(n); }
  void observeMaximum(int id, double v) noexcept override { values_[id] = std::max(values_[id], v); }
  void setValue(int id, double v) noexcept override { values_[id] = v; }
  double value(const std::string& name) const {
    for (int i = 0; i < count_; ++i)
      if (name == names_[i]) return values_[i];
    FAIL("no figure " << name);
    return 0.0;
  }
  FigureKind kind(const std::string& name) const {
    for (int i = 0; i < count_; ++i)
      if (name == names_[i]) return kinds_[i];
    return FigureKind::kCount;
  }
  int size() const { return count_; }

 private:
  std::array<const char*, 16> names_{};
  std::array<FigureKind, 16> kinds_{};
  std::array<double, 16> values_{};
  int count_ = 0;
};

PassivePolicy::Options layerOptions(int actuators, double max_damping, bool damping = true) {
  PassivePolicy::Options o;
  o.actuators = actuators;
  o.controller.enabled = damping;
  o.controller.max_damping = max_damping;
  o.controller.effort_limit = Eigen::VectorXd::Constant(actuators, 1.0);
  return o;
}

// One joint of inertia J and viscous friction b (actuated), and a sensed-only joint that follows it
// at half its angle (an underactuated linkage), pressed by a hand against the sampled wall at
// q = 0 with a constant torque and then released. K T / 2 = 4.5 b: beyond Colgate's bound b > K T / 2
// (K above 2 b / T), so the wall alone is active. Rates: the backward difference of the sensed
// positions; 20 substeps per period. Returns the net work the applied efforts did on the joint.
struct PressRun {
  double generated = 0.0;       // net true work of the applied efforts over the run [J]
  double peak_generated = 0.0;  // its largest value [J]
  double peak_observed = 0.0;   // the layer's worst report of net generated energy [J]
  std::uint64_t active_ticks = 0;
};

constexpr double kJ = 5e-5, kB = 5e-4, kK = 4.5, kHand = 0.045, kGap = 0.01;
constexpr double kMaxDamping = 0.01;  // N m s/rad: 0.2 J / T, far inside what a servo renders on J

PressRun pressAndRelease(bool layer, bool damping, RecordingFigures& figures) {
  constexpr int kSub = 20, kPress = 2000, kTicks = 3000;
  const double h = kT / kSub;
  auto wall = std::make_unique<JointWallPolicy>(1, kK);
  std::unique_ptr<DevicePolicy> policy = std::move(wall);
  PassivePolicy* passive = nullptr;
  if (layer) {
    auto p = std::make_unique<PassivePolicy>(std::move(policy), layerOptions(1, kMaxDamping, damping), figures);
    passive = p.get();
    policy = std::move(p);
  }
  policy->reset(0);
  double q = -kGap, v = 0.0, previous = q;
  PressRun run;
  SensedState state;
  for (int k = 0; k < kTicks; ++k) {
    const double positions[2] = {q, 0.5 * q};
    const double rates[2] = {k == 0 ? 0.0 : (q - previous) / kT, k == 0 ? 0.0 : 0.5 * (q - previous) / kT};
    previous = q;
    policy->sense(SensedJoints{positions, rates, k == 0}, state);
    SceneInput input;
    input.dt = kT;
    input.time = k * kT;
    double effort[1] = {0.0};
    if (policy->render(input, effort) != Fault::kNone) effort[0] = 0.0;
    const double hand = k < kPress ? kHand : 0.0;
    const double q_start = q;
    for (int s = 0; s < kSub; ++s) {  // semi-implicit Euler
      v += h * (effort[0] + hand - kB * v) / kJ;
      q += h * v;
    }
    run.generated += effort[0] * (q - q_start);
    run.peak_generated = std::max(run.peak_generated, run.generated);
  }
  if (passive) {
    run.peak_observed = passive->controller().peakEnergyOut();
    run.active_ticks = passive->controller().activeTicks();
  }
  return run;
}

}  // namespace

TEST_CASE("passive policy: observing only, the efforts are bit for bit the wrapped policy's") {
  RecordingFigures figures;
  auto wrapped = std::make_unique<JointWallPolicy>(3, 50.0);
  JointWallPolicy reference(3, 50.0);
  JointWallPolicy* inner = wrapped.get();
  PassivePolicy layer(std::move(wrapped), layerOptions(3, 1e3, false), figures);
  layer.reset(0);
  reference.reset(0);
  std::mt19937 rng(29);
  std::uniform_real_distribution<double> uniform(-2.0, 2.0);  // beyond the 1.0 limits too
  bool identical = true;
  SensedState state, reference_state;
  for (int k = 0; k < 5000; ++k) {
    const double positions[4] = {uniform(rng), uniform(rng), uniform(rng), uniform(rng)};
    const double rates[4] = {uniform(rng), uniform(rng), uniform(rng), uniform(rng)};
    inner->others = reference.others = uniform(rng);
    layer.sense(SensedJoints{positions, rates, k == 0}, state);
    reference.sense(SensedJoints{positions, rates, k == 0}, reference_state);
    SceneInput input;
    input.dt = kT;
    double efforts[3], expected[3];
    REQUIRE(layer.render(input, efforts) == Fault::kNone);
    reference.render(input, expected);
    identical = identical && std::memcmp(efforts, expected, sizeof efforts) == 0;
  }
  CHECK(identical);
  CHECK(layer.controller().activeTicks() == 0);
  CHECK(figures.value("passivity_active_ticks") == 0.0);
  CHECK(layer.name() == "joint wall + passivity");
  CHECK(inner->resets == 1);
}

TEST_CASE("passive policy: a sampled wall above 2b/T goes active alone and is passive with the layer") {
  REQUIRE(kK > 2.0 * kB / kT);
  RecordingFigures unused;
  const PressRun bare = pressAndRelease(false, false, unused);
  RecordingFigures observing_figures;
  const PressRun observed = pressAndRelease(true, false, observing_figures);
  RecordingFigures figures;
  const PressRun passive = pressAndRelease(true, true, figures);

  // Alone (and with the layer only observing, which changes nothing) the wall gives out energy.
  CHECK(bare.generated > 1e-2);
  CHECK(observed.generated == bare.generated);
  CHECK(observed.peak_observed > 1e-2);
  // With the layer the press and the release generate at most 1 mJ, true work and observed alike:
  // the observer never reports below -1 mJ of the energy the device absorbed.
  INFO("generated " << passive.generated << " J, peak " << passive.peak_generated << " J, observed peak "
                    << passive.peak_observed << " J");
  CHECK(passive.generated <= 1e-3);
  CHECK(passive.peak_generated <= 1e-3);
  CHECK(passive.peak_observed <= 1e-3);
  CHECK(passive.active_ticks > 0);
  // The figures carry the same trace, in mJ.
  CHECK(figures.value("passivity_peak_energy_out_mJ") == Approx(1e3 * passive.peak_observed));
  CHECK(figures.value("passivity_active_ticks") == static_cast<double>(passive.active_ticks));
  CHECK(figures.value("passivity_dissipated_mJ") > 0.0);
  CHECK(figures.value("passivity_max_damping") > 0.0);
  CHECK(figures.value("passivity_max_damping") <= kMaxDamping);
  CHECK(figures.value("passivity_faults") == 0.0);
  CHECK(figures.kind("passivity_energy_out_mJ") == FigureKind::kValue);
  CHECK(figures.size() == 6);
}

TEST_CASE("passive policy: a million hostile ticks give finite efforts within the limits, zero on a fault") {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  const double specials[] = {0.0, -0.0, std::numeric_limits<double>::denorm_min(), 1e-12, nan, inf, -inf, 50.0};
  std::mt19937_64 rng(2002);
  std::uniform_real_distribution<double> uniform(-5.0, 5.0);
  std::uniform_int_distribution<int> pick(0, 4 * static_cast<int>(std::size(specials)));
  const auto draw = [&] {
    const int i = pick(rng);
    return i < static_cast<int>(std::size(specials)) ? specials[i] : uniform(rng);
  };
  RecordingFigures figures;
  auto wrapped = std::make_unique<JointWallPolicy>(2, 20.0);
  JointWallPolicy* inner = wrapped.get();
  PassivePolicy layer(std::move(wrapped), layerOptions(2, 5.0), figures);
  layer.reset(0);
  SensedState state;
  double effort_override = 0.0;
  std::uint64_t non_finite = 0, over_limit = 0, nonzero_fault = 0, damped_at_rest = 0, expected_faults = 0,
                zero_rate_ticks = 0;
  for (int k = 0; k < 1000000; ++k) {
    const double positions[3] = {draw(), draw(), draw()};
    // Exactly zero rates on every fourth tick: the guard must hold there, whatever the energy.
    const double rates[3] = {k % 4 == 0 ? 0.0 : draw(), k % 4 == 0 ? 0.0 : draw(), draw()};
    zero_rate_ticks += k % 4 == 0;
    effort_override = draw();
    inner->override_effort = k % 3 == 0 ? &effort_override : nullptr;
    inner->others = draw();
    layer.sense(SensedJoints{positions, rates, k == 0}, state);
    SceneInput input;
    input.dt = kT;
    double efforts[2] = {0.0, 0.0};
    const Fault fault = layer.render(input, efforts);
    // What the controller sees: the actuated joints' positions and rates, and the wall's efforts.
    const double wall = inner->override_effort ? effort_override : (positions[0] > 0.0 ? -20.0 * positions[0] : 0.0);
    const bool hostile = !std::isfinite(positions[0]) || !std::isfinite(positions[1]) || !std::isfinite(rates[0]) ||
                         !std::isfinite(rates[1]) || !std::isfinite(wall) || !std::isfinite(inner->others);
    expected_faults += hostile;
    non_finite += !std::isfinite(efforts[0]) || !std::isfinite(efforts[1]);
    over_limit += std::abs(efforts[0]) > 1.0 || std::abs(efforts[1]) > 1.0;
    if (fault != Fault::kNone) nonzero_fault += efforts[0] != 0.0 || efforts[1] != 0.0;
    if (k % 4 == 0 && !hostile) {
      // No damping at exactly zero rate: the command is the held wall effort.
      damped_at_rest += efforts[0] != std::clamp(wall, -1.0, 1.0);
    }
  }
  CHECK(non_finite == 0);
  CHECK(over_limit == 0);
  CHECK(nonzero_fault == 0);
  CHECK(damped_at_rest == 0);
  CHECK(zero_rate_ticks == 250000);
  CHECK(expected_faults > 0);
  CHECK(layer.controller().faults() == expected_faults);
  CHECK(figures.value("passivity_faults") == static_cast<double>(expected_faults));
  CHECK(layer.controller().activeTicks() > 0);
  CHECK(std::isfinite(layer.controller().energyOut()));
  CHECK(std::isfinite(figures.value("passivity_energy_out_mJ")));
}

TEST_CASE("passive policy: periods it did not command are left out of the observation") {
  RecordingFigures figures;
  auto wrapped = std::make_unique<JointWallPolicy>(1, 0.0);
  JointWallPolicy* inner = wrapped.get();
  PassivePolicy layer(std::move(wrapped), layerOptions(1, 0.0), figures);  // cap 0: observe the work only
  layer.reset(0);
  const double effort = 0.5;
  inner->override_effort = &effort;
  SensedState state;
  const double still[2] = {0.0, 0.0};
  double q = 0.0;
  const auto tick = [&](bool render) {
    const double positions[2] = {q, 0.0};
    layer.sense(SensedJoints{positions, still, false}, state);
    double out[1];
    SceneInput input;
    input.dt = kT;
    if (render) layer.render(input, out);
  };
  tick(true);
  q = 0.1;
  tick(true);
  CHECK(layer.controller().energyOut() == Approx(0.05).epsilon(1e-12));
  // A reading that got no render (the caller ramped its last efforts down): the motion up to the
  // next reading is not this layer's command's work.
  q = 0.3;
  tick(false);
  q = 0.6;
  tick(true);
  CHECK(layer.controller().energyOut() == Approx(0.05).epsilon(1e-12));
  q = 0.7;
  tick(true);
  CHECK(layer.controller().energyOut() == Approx(0.1).epsilon(1e-12));
  // A lost reading: likewise.
  layer.readingLost();
  CHECK(inner->lost == 1);
  q = 2.0;
  tick(true);
  CHECK(layer.controller().energyOut() == Approx(0.1).epsilon(1e-12));
  // A wrapped fault: the caller sends zero, the layer observes zero and passes the fault on.
  inner->fault = Fault::kSingular;
  const double positions[2] = {2.5, 0.0};
  layer.sense(SensedJoints{positions, still, false}, state);
  double out[1] = {9.0};
  SceneInput input;
  input.dt = kT;
  CHECK(layer.render(input, out) == Fault::kSingular);
  CHECK(out[0] == 0.0);
  CHECK(layer.controller().energyOut() == Approx(0.1 + 0.25).epsilon(1e-12));
  inner->fault = Fault::kNone;
  q = 3.0;
  tick(true);
  CHECK(layer.controller().energyOut() == Approx(0.35).epsilon(1e-12));  // zero did no work
  CHECK(layer.controller().faults() == 0);
  CHECK(figures.value("passivity_energy_out_mJ") == Approx(350.0));
  // A new session starts a new observation.
  layer.reset(1);
  CHECK(layer.controller().energyOut() == 0.0);
}

TEST_CASE("passive policy: bad set-up is refused") {
  RecordingFigures figures;
  CHECK_THROWS_AS(PassivePolicy(nullptr, layerOptions(1, 1.0), figures), Error);
  CHECK_THROWS_AS(PassivePolicy(std::make_unique<JointWallPolicy>(1, 1.0), layerOptions(0, 1.0), figures), Error);
  PassivePolicy::Options too_many;  // no per-joint vectors: they hold at most kMaxSensedJoints
  too_many.actuators = kMaxSensedJoints + 1;
  CHECK_THROWS_AS(PassivePolicy(std::make_unique<JointWallPolicy>(1, 1.0), too_many, figures), Error);
  PassivePolicy::Options o = layerOptions(2, 1.0);
  o.controller.effort_limit = Eigen::VectorXd::Constant(3, 1.0);  // one per actuator, not three
  CHECK_THROWS_AS(PassivePolicy(std::make_unique<JointWallPolicy>(2, 1.0), o, figures), Error);
  RecordingFigures fresh;
  PassivePolicy layer(std::make_unique<JointWallPolicy>(2, 1.0), layerOptions(2, 1.0), fresh);
  o.controller.max_damping = -1.0;
  o.controller.effort_limit.resize(0);
  CHECK_THROWS_AS(layer.configure(o), Error);
}

TEST_CASE("passive policy: a servo tick allocates nothing") {
  auto wrapped = std::make_unique<JointWallPolicy>(6, 30.0);
  PassivePolicy layer(std::move(wrapped), layerOptions(6, 2.0), FigureRecorder::none());
  layer.reset(0);
  SensedState state;
  state.joints.resize(7);
  double q = 0.01;
  std::uint64_t allocations = 0;
  {
    tools::AllocationScope scope;
    for (int k = 0; k < 2000; ++k) {
      const double positions[7] = {q, q, q, q, q, q, q};
      const double rates[7] = {0.3, 0.3, 0.3, 0.3, 0.3, 0.3, 0.3};
      layer.sense(SensedJoints{positions, rates, k == 0}, state);
      SceneInput input;
      input.dt = kT;
      double efforts[6];
      layer.render(input, efforts);
      q += 3e-4 * (k % 50 < 25 ? 1.0 : -1.0);
    }
    allocations = scope.count();
  }
  CHECK(allocations == 0);
  CHECK(layer.controller().activeTicks() > 0);
}

TEST_CASE("passivityDampingCaps: the damping stated at the tool, seen at each actuated joint, bad counts refused") {
  // The wall policy's tool is joint 0's position along x (dp/dq0 = 1) and turns with no joint: joint
  // 0's cap is the linear damping, joint 1's is 0 whatever the angular damping.
  JointWallPolicy policy(2, 100.0);
  const std::array<double, 3> rest{0.01, 0.2, 0.3};
  std::vector<double> caps = passivityDampingCaps(policy, rest.data(), 3, 2, 4.0, 1.0);
  REQUIRE(caps.size() == 2);
  CHECK(caps[0] == Approx(4.0).epsilon(1e-9));
  CHECK(caps[1] == 0.0);
  caps = passivityDampingCaps(policy, rest.data(), 3, 2, std::nan(""), -1.0);  // unstated: no damping
  CHECK(caps == std::vector<double>{0.0, 0.0});
  CHECK_THROWS_AS(passivityDampingCaps(policy, rest.data(), 2, 3, 4.0, 0.0), Error);  // more actuators than joints
  CHECK_THROWS_AS(passivityDampingCaps(policy, rest.data(), 0, 0, 4.0, 0.0), Error);
}
