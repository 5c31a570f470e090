// The passivity layer in the servo path (uhaptics::PassivePolicy) around a joint-space policy: bit for
// bit when it only observes, an active sampled wall made passive with and without command delay, its
// booking against the plant's true port work, the policy's own field left alone, a million ticks of
// hostile input, the observation chain across periods it did not command, and no allocation per tick.
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

// A joint-space wall on joint 0 at q = 0 (efforts -K q0 inside it) plus a field of its own on joint
// 0 (`own`, reported by ownEfforts()); the other actuators get `others`. It can be told to return a
// fault or a non-finite effort, and states a diagonal joint inertia when `inertia` > 0.
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
    efforts[0] = (q0_ > 0.0 ? -stiffness_ * q0_ : 0.0) + own;
    for (int i = 1; i < actuators_; ++i) efforts[i] = others;
    if (override_effort) efforts[0] = *override_effort;
    return fault;
  }
  void readingLost() noexcept override { ++lost; }
  void commandApplied(int periods_ago) noexcept override { applied = periods_ago; }
  void ownEfforts(double* efforts) const noexcept override { efforts[0] += own; }
  bool actuatedInertia(double* matrix) const override {
    if (!(inertia > 0.0)) return false;
    for (int i = 0; i < actuators_; ++i)
      for (int j = 0; j < actuators_; ++j) matrix[i + j * actuators_] = i == j ? inertia : 0.0;
    return true;
  }

  Fault fault = Fault::kNone;
  double others = 0.0;
  double own = 0.0;
  double inertia = 0.0;
  const double* override_effort = nullptr;
  int resets = 0, lost = 0, applied = -1;

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
// q = 0 with a constant torque and then released; the plant applies each command `delay` periods
// after the reading it was computed from. K T (1 + 2 d) / 2 = 4.5 b: beyond Colgate's bound
// b > K T (1 + 2 d) / 2, so the wall alone is active. The layer's cap is the joint's inertia's
// (J / (2 T (1 + d))). 20 substeps per period.
struct PressRun {
  double generated = 0.0;       // net true work of the applied efforts over the run [J]
  double peak_generated = 0.0;  // its largest value [J]
  double booked = 0.0;          // the layer's booked port work [J]
  std::uint64_t active_ticks = 0;
};

constexpr double kJ = 5e-5, kB = 5e-4, kK = 4.5, kHand = 0.045, kGap = 0.01;

PressRun pressAndRelease(bool layer, bool damping, RecordingFigures& figures, int delay = 0, int layer_delay = -1) {
  constexpr int kSub = 20, kPress = 2000, kTicks = 3000;
  const double h = kT / kSub;
  auto wall = std::make_unique<JointWallPolicy>(1, kK / (1 + 2 * delay));
  wall->inertia = kJ;
  std::unique_ptr<DevicePolicy> policy = std::move(wall);
  PassivePolicy* passive = nullptr;
  if (layer) {
    PassivePolicy::Options o = layerOptions(1, std::nan(""), damping);
    const double rest[2] = {-kGap, -0.5 * kGap};
    o = passivePolicyOptions(*policy, rest, 2, 1, o.controller);
    auto p = std::make_unique<PassivePolicy>(std::move(policy), o, figures);
    passive = p.get();
    policy = std::move(p);
  }
  policy->reset(layer_delay >= 0 ? layer_delay : delay);
  double q = -kGap, v = 0.0;
  std::array<double, 4> pipeline{};  // commands in flight, newest first
  PressRun run;
  SensedState state;
  const double still[2] = {0.0, 0.0};  // the layer brakes on displacements, not on these
  for (int k = 0; k < kTicks; ++k) {
    const double positions[2] = {q, 0.5 * q};
    policy->sense(SensedJoints{positions, still, k == 0}, state);
    SceneInput input;
    input.dt = kT;
    input.time = k * kT;
    double effort[1] = {0.0};
    if (policy->render(input, effort) != Fault::kNone) effort[0] = 0.0;
    for (int i = 3; i > 0; --i) pipeline[i] = pipeline[i - 1];
    pipeline[0] = effort[0];
    const double applied = pipeline[static_cast<std::size_t>(delay)];
    const double hand = k < kPress ? kHand : 0.0;
    const double q_start = q;
    for (int s = 0; s < kSub; ++s) {  // semi-implicit Euler
      v += h * (applied + hand - kB * v) / kJ;
      q += h * v;
    }
    run.generated += applied * (q - q_start);
    run.peak_generated = std::max(run.peak_generated, run.generated);
  }
  if (passive) {
    run.booked = passive->controller().bookedWork();
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
  // The board's report of the command it applied reaches the wrapped policy (the TAU's wall uses it).
  layer.commandApplied(2);
  CHECK(inner->applied == 2);
}

TEST_CASE("passive policy: a sampled wall above 2b/T goes active alone and is passive with the layer") {
  for (const int delay : {0, 1}) {
    REQUIRE(kK / (1 + 2 * delay) > 2.0 * kB / ((1 + 2 * delay) * kT));
    INFO("command delay " << delay);
    RecordingFigures unused;
    const PressRun bare = pressAndRelease(false, false, unused, delay);
    RecordingFigures observing_figures;
    const PressRun observed = pressAndRelease(true, false, observing_figures, delay);
    RecordingFigures figures;
    const PressRun passive = pressAndRelease(true, true, figures, delay);

    // Alone (and with the layer only observing, which changes nothing) the wall gives out energy.
    CHECK(bare.generated > 1e-2);
    CHECK(observed.generated == bare.generated);
    CHECK(observing_figures.value("passivity_generated_mJ") > 1e3 * 1e-2);
    // With the layer the press and the release generate at most 1 mJ at the end and at every period.
    INFO("generated " << passive.generated << " J, peak " << passive.peak_generated << " J");
    CHECK(passive.generated <= 1e-3);
    CHECK(passive.peak_generated <= 1e-3);
    CHECK(passive.active_ticks > 0);
    // The figures carry the same trace, in mJ; the damping stays under the inertia's cap.
    CHECK(figures.value("passivity_energy_out_mJ") == Approx(1e3 * passive.booked));
    CHECK(figures.value("passivity_active_ticks") == static_cast<double>(passive.active_ticks));
    CHECK(figures.value("passivity_dissipated_mJ") > 0.0);
    CHECK(figures.value("passivity_max_damping") > 0.0);
    CHECK(figures.value("passivity_max_damping") <= kJ / (2.0 * kT * (1.0 + delay)) * (1.0 + 1e-12));
    CHECK(figures.value("passivity_faults") == 0.0);
    CHECK(figures.kind("passivity_energy_out_mJ") == FigureKind::kValue);
    CHECK(figures.kind("passivity_peak_excess_mJ") == FigureKind::kMaximum);
    CHECK(figures.size() == 7);
  }
}

TEST_CASE("passive policy: at a command delay of one period the booked work is the plant's true port work") {
  // The layer books the command the plant applied (sent one period before); observing only, so the
  // plant's motion is the wall's alone.
  RecordingFigures aligned_figures, misaligned_figures;
  const PressRun aligned = pressAndRelease(true, false, aligned_figures, 1);
  const PressRun misaligned = pressAndRelease(true, false, misaligned_figures, 1, 0);  // told 0
  INFO("true " << aligned.generated << " J, booked " << aligned.booked << " J, booked as if undelayed "
               << misaligned.booked << " J");
  REQUIRE(std::abs(aligned.generated) > 1e-2);
  CHECK(aligned.booked == Approx(aligned.generated).epsilon(0.05));
  CHECK_FALSE(misaligned.booked == Approx(aligned.generated).epsilon(0.05));
}

TEST_CASE("passive policy: the policy's own field is neither observed nor damped") {
  // No scene effort (the joint stays outside the wall) while the policy's own field pushes the joint
  // about: nothing booked, no damping, efforts bit for bit.
  RecordingFigures figures;
  auto wrapped = std::make_unique<JointWallPolicy>(1, 50.0);
  JointWallPolicy* inner = wrapped.get();
  PassivePolicy::Options o = layerOptions(1, 1.0);
  PassivePolicy layer(std::move(wrapped), o, figures);
  layer.reset(0);
  SensedState state;
  const double still[2] = {0.0, 0.0};
  bool identical = true;
  for (int k = 0; k < 2000; ++k) {
    const double q = -0.1 + 0.05 * std::sin(0.01 * k);
    inner->own = 0.4 * std::cos(0.013 * k);
    const double positions[2] = {q, 0.0};
    layer.sense(SensedJoints{positions, still, k == 0}, state);
    SceneInput input;
    input.dt = kT;
    double effort[1];
    REQUIRE(layer.render(input, effort) == Fault::kNone);
    identical = identical && effort[0] == inner->own;
  }
  CHECK(identical);
  CHECK(layer.controller().activeTicks() == 0);
  CHECK(layer.controller().bookedWork() == 0.0);
  CHECK(layer.controller().generated() == 0.0);
  CHECK(figures.value("passivity_active_ticks") == 0.0);
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
                still_ticks = 0;
  double positions[3] = {0.0, 0.0, 0.0};
  const double rates[3] = {0.0, 0.0, 0.0};
  bool previous_valid = false;
  for (int k = 0; k < 1000000; ++k) {
    // The same reading again on every fourth tick: no displacement, so no damping, whatever the energy.
    const bool still = k % 4 == 0 && previous_valid;
    if (!still)
      for (double& p : positions) p = draw();
    still_ticks += still;
    effort_override = draw();
    inner->override_effort = k % 3 == 0 ? &effort_override : nullptr;
    inner->others = draw();
    layer.sense(SensedJoints{positions, rates, k == 0}, state);
    SceneInput input;
    input.dt = kT;
    double efforts[2] = {0.0, 0.0};
    const Fault fault = layer.render(input, efforts);
    // What the layer sees: the actuated joints' positions and the wall's efforts.
    const double wall = inner->override_effort ? effort_override : (positions[0] > 0.0 ? -20.0 * positions[0] : 0.0);
    const bool hostile = !std::isfinite(positions[0]) || !std::isfinite(positions[1]) || !std::isfinite(wall) ||
                         !std::isfinite(inner->others);
    previous_valid = std::isfinite(positions[0]) && std::isfinite(positions[1]);
    expected_faults += hostile;
    non_finite += !std::isfinite(efforts[0]) || !std::isfinite(efforts[1]);
    over_limit += std::abs(efforts[0]) > 1.0 || std::abs(efforts[1]) > 1.0;
    if (fault != Fault::kNone) nonzero_fault += efforts[0] != 0.0 || efforts[1] != 0.0;
    if (still && !hostile) damped_at_rest += efforts[0] != std::clamp(wall, -1.0, 1.0);
  }
  CHECK(non_finite == 0);
  CHECK(over_limit == 0);
  CHECK(nonzero_fault == 0);
  CHECK(damped_at_rest == 0);
  CHECK(still_ticks > 200000);
  CHECK(expected_faults > 0);
  CHECK(layer.controller().faults() == expected_faults);
  CHECK(figures.value("passivity_faults") == static_cast<double>(expected_faults));
  CHECK(layer.controller().activeTicks() > 0);
  CHECK(std::isfinite(layer.controller().bookedWork()));
  CHECK(std::isfinite(figures.value("passivity_energy_out_mJ")));
  CHECK(std::isfinite(figures.value("passivity_generated_mJ")));
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
  CHECK(layer.controller().bookedWork() == Approx(0.05).epsilon(1e-12));
  // A reading that got no render (the caller ramped its last efforts down): the motion up to the
  // next reading is not this layer's command's work.
  q = 0.3;
  tick(false);
  q = 0.6;
  tick(true);
  CHECK(layer.controller().bookedWork() == Approx(0.05).epsilon(1e-12));
  q = 0.7;
  tick(true);
  CHECK(layer.controller().bookedWork() == Approx(0.1).epsilon(1e-12));
  // A lost reading: likewise.
  layer.readingLost();
  CHECK(inner->lost == 1);
  q = 2.0;
  tick(true);
  CHECK(layer.controller().bookedWork() == Approx(0.1).epsilon(1e-12));
  // A wrapped fault: the caller sends zero, a command the layer did not shape, and the fault is passed on.
  inner->fault = Fault::kSingular;
  const double positions[2] = {2.5, 0.0};
  layer.sense(SensedJoints{positions, still, false}, state);
  double out[1] = {9.0};
  SceneInput input;
  input.dt = kT;
  CHECK(layer.render(input, out) == Fault::kSingular);
  CHECK(out[0] == 0.0);
  inner->fault = Fault::kNone;
  q = 3.0;
  tick(true);
  q = 3.2;
  tick(true);
  CHECK(layer.controller().bookedWork() == Approx(0.2).epsilon(1e-12));  // 2.0 -> 2.5 -> 3.0 not booked
  CHECK(layer.controller().faults() == 0);
  CHECK(figures.value("passivity_energy_out_mJ") == Approx(200.0));
  // A new session starts a new observation.
  layer.reset(1);
  CHECK(layer.controller().bookedWork() == 0.0);
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
  CHECK_THROWS_AS(layer.reset(kScenePortMaxDelay + 1), Error);  // a delay it cannot align with
}

TEST_CASE("passive policy: a servo tick allocates nothing") {
  auto wrapped = std::make_unique<JointWallPolicy>(6, 30.0);
  PassivePolicy layer(std::move(wrapped), layerOptions(6, 2.0), FigureRecorder::none());
  layer.reset(1);
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

TEST_CASE("passivePolicyOptions: the board's limits and steps with the policy's inertia at rest") {
  JointWallPolicy policy(2, 100.0);
  const std::array<double, 3> rest{0.01, 0.2, 0.3};
  ScenePortPassivityOptions board;
  board.effort_limit = Eigen::VectorXd::Constant(2, 3.0);
  board.resolution = Eigen::VectorXd::Constant(2, 1e-3);
  PassivePolicy::Options o = passivePolicyOptions(policy, rest.data(), 3, 2, board);
  CHECK(o.actuators == 2);
  CHECK(o.controller.inertia.size() == 0);  // a policy without dynamics: observe only
  CHECK(o.controller.effort_limit == board.effort_limit);
  CHECK(o.controller.resolution == board.resolution);
  policy.inertia = 0.02;
  o = passivePolicyOptions(policy, rest.data(), 3, 2, board);
  REQUIRE(o.controller.inertia.rows() == 2);
  CHECK(o.controller.inertia.isApprox(Eigen::Matrix2d::Identity() * 0.02));
  CHECK_THROWS_AS(passivePolicyOptions(policy, rest.data(), 2, 3, board), Error);  // more actuators than joints
  CHECK_THROWS_AS(passivePolicyOptions(policy, rest.data(), 0, 0, board), Error);
}
