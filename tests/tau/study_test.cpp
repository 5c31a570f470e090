// Paper 001's requirements on a reduced grid, plus the interactive properties uhaptics adds
// (release without attraction, sliding without sticking).
#include <catch2/catch.hpp>

#include "device_servo_renderers.hpp"
#include "renderer_fixtures.hpp"
#include "uhaptics/backends/board_catalog.hpp"
#include "uhaptics/core/limits.hpp"
#include "uhaptics/experiments/tau_study.hpp"
#include "uhaptics/renderers/lqr_wall_renderer.hpp"
#include "uhaptics/renderers/tau_wall_design.hpp"

using namespace uhaptics;
using namespace uhaptics::study;

namespace {
// The TAU as the product runs it: the devices' policy factory on the shipped parameter file.
const TauProduct& tauProduct() {
  static const DeviceDefinition& tau = *findDeviceByPaper("001");
  static const TauProduct product{[] { return makeDevicePolicy(tau, test::paramsDir()); },
                                  boardSpec(tau, test::paramsDir())};
  return product;
}
// Paper 001's controller with the default weights, undelayed.
StudyDevice& undelayedDevice() {
  static StudyDevice device(tauProduct(), studyWallDesign({}, StudyParameters{}.contact_band), 0);
  return device;
}
// The random-delay design of the CoS-D runs: d ~ U{0..3}, input-rate weight 200, the study's observer.
StudyDevice& randomDelayDevice() {
  static StudyDevice device(tauProduct(), [] {
    TauPolicy::WallDesign design = studyWallDesign({}, StudyParameters{}.contact_band);
    design.random_delay = true;
    design.delay_rate_weight = 200.0;
    design.custom_observer_noise = true;
    return design;
  }(), 3);
  return device;
}
}  // namespace

TEST_CASE("Study, reduced grid: LQR penetration < 1 mm and K_zs an order above the spring wall") {
  // Scenario 1 (the 15 N step, the hard case for the torques) at the four corners of the wall,
  // where the static torque peaks, and scenario 2 at the centre: 10 runs of 3 s, ~0.3 s CPU, kept
  // small because the sanitizer builds run it ~10x slower on shared cores (120 s ctest timeout).
  // uhaptics-tau-study covers the whole 11 x 11 grid x 20 runs.
  double lqr_pen = 0.0, lqr_kzs_min = 1e300, spring_kzs_max = 0.0;
  const double c = test::tauModel().workspaceHalfSide();
  struct Case {
    double x, y;
    Scenario scenario;
  };
  const Case cases[] = {{-c, -c, Scenario::kStepForce}, {-c, c, Scenario::kStepForce}, {c, -c, Scenario::kStepForce},
                        {c, c, Scenario::kStepForce},   {0.0, 0.0, Scenario::kHand}};
  for (const Case& k : cases) {
    RunSpec spec;
    spec.x = k.x;
    spec.y = k.y;
    spec.seed = 11;
    spec.scenario = k.scenario;
    const RunMetrics lqr = simulateRun(test::tauModel(), undelayedDevice(), spec);
    spec.controller = Controller::kSpring;
    const RunMetrics spring = simulateRun(test::tauModel(), undelayedDevice(), spec);
    INFO("x " << k.x << " y " << k.y << " scenario " << static_cast<int>(k.scenario));
    CHECK(lqr.fault == Fault::kNone);
    // The baseline renders only the normal spring; its free directions stay in the workspace
    // because the device damps them (StudyParameters::device_rotational_damping).
    CHECK(spring.fault == Fault::kNone);
    lqr_pen = std::max(lqr_pen, lqr.max_penetration);
    lqr_kzs_min = std::min(lqr_kzs_min, lqr.k_zs);
    spring_kzs_max = std::max(spring_kzs_max, spring.k_zs);
  }
  WARN("reduced grid: LQR max penetration " << lqr_pen * 1e3 << " mm, lowest LQR K_zs " << lqr_kzs_min
                                            << " N/m, highest spring K_zs " << spring_kzs_max << " N/m");
  CHECK(lqr_pen < 1e-3);                          // paper 001: penetration < 1 mm
  CHECK(lqr_kzs_min > 10.0 * spring_kzs_max);     // paper: >= 10x (Table IV: 15x and 10x)
  CHECK(spring_kzs_max == Approx(6000.0).epsilon(0.15));  // the baseline renders its design stiffness
}

TEST_CASE("Study runs are exactly repeatable for a seed") {
  RunSpec spec;
  spec.seed = 99;
  spec.max_delay_samples = 3;
  const RunMetrics a = simulateRun(test::tauModel(), randomDelayDevice(), spec);
  const RunMetrics b = simulateRun(test::tauModel(), randomDelayDevice(), spec);
  CHECK(a.d_z1 == b.d_z1);
  CHECK(a.k_zs == b.k_zs);
  CHECK(a.referee.generated_energy_mJ == b.referee.generated_energy_mJ);
  spec.seed = 100;
  CHECK(simulateRun(test::tauModel(), randomDelayDevice(), spec).force_level != a.force_level);
}

namespace {
// A hand (spring-damper, paper values) holds the tool: pushes 10 N into the wall z = 0, slides
// 10 mm along x, then pulls away. Returns what the tests assert.
struct Interaction {
  double max_penetration_push = 0.0;
  double slide_distance = 0.0;
  double max_tangential_hand_force = 0.0;
  int contact_ticks_after_release = 0;  // the wall engaged while the hand pulls the tool off it
  int attractive_ticks = 0;
  double max_height = 0.0;  // m, the tool's highest point
};
Interaction interact(bool quantize) {
  SimulatedTauOptions so;
  so.quantize = quantize;
  // The handle's rotational damping, as the board plant simulates it: the hand holds only the
  // tool's position, and after lift-off nothing else keeps its orientation from drifting on the
  // encoders' quantization.
  so.tool_rotational_damping = 0.01;
  SimulatedTau sim(test::tauModel(), so);
  LqrWallRenderer renderer(test::tauModel(), test::tauHomeGains());
  TauData device(test::tauModel());
  SurfaceContact contact;
  Vec3 hand = sim.pose().head<3>();
  Interaction out;
  double x_start = 0.0;
  for (int k = 0; k < 2500; ++k) {
    const double t = k * 1e-3;
    test::tauModel().forward(sim.encoderReading(), device);
    test::tauModel().computeGravity(sim.encoderReading(), device);
    contact.active = device.pose(2) <= 1e-3;
    contact.point = Vec3(device.pose(0), device.pose(1), 0.0);
    const WallCommand& cmd = renderer.tick(sim.encoderReading(), contact, &device.pose);
    REQUIRE(cmd.fault == Fault::kNone);
    // Attraction: a contact force (beyond gravity compensation) pulling the tool into the wall.
    const Vec6 wall_force = device.J.transpose().partialPivLu().solve(cmd.torque - device.gravity);
    if (cmd.in_contact && device.pose(2) > 0.0 && wall_force(2) < -0.5) ++out.attractive_ticks;
    Vec3 hv = Vec3::Zero();
    if (t < 1.0) hv.z() = -0.25;  // 0.25 m into the wall x 40 N/m = 10 N
    else if (t < 1.5) hv.x() = 0.02;
    // Pull away: the hand ends 10 mm above the wall, and the tool it tows overshoots it by about
    // 12 mm (hand spring 40 N/m): the path stays inside paper 001's 50 mm workspace cube, out of
    // which the forward kinematics rightly refuse the pose (kOutOfRange).
    else if (t < 2.0) hv.z() = 0.52;
    sim.setHand(hand, hv, Vec3::Zero());
    hand += hv * 1e-3;
    sim.step(cmd.torque, Vec3::Zero());
    if (t > 0.5 && t < 1.0) out.max_penetration_push = std::max(out.max_penetration_push, -sim.pose()(2));
    if (t < 1.0) x_start = sim.pose()(0);
    if (t >= 1.0 && t < 1.6) out.max_tangential_hand_force = std::max(out.max_tangential_hand_force, std::abs(sim.handForce().x()));
    if (t > 1.6 && t < 1.7) out.slide_distance = sim.pose()(0) - x_start;
    // Released: the hand pulls the tool away from the wall by more than 0.5 N (its spring has risen
    // past the tool: from about 1.98 s; before, it still presses the tool on the wall).
    if (cmd.in_contact && sim.handForce().z() > 0.5) ++out.contact_ticks_after_release;
    out.max_height = std::max(out.max_height, sim.pose()(2));
  }
  return out;
}
}  // namespace

TEST_CASE("LQR wall: holds a 10 N push, lets the tool slide, releases without attraction") {
  for (bool quantize : {false, true}) {
    const Interaction r = interact(quantize);
    INFO("quantized encoders: " << quantize);
    CHECK(r.max_penetration_push < 1e-3);
    // The hand moved 10 mm along the wall; the tool follows within 2 mm (hand spring 40 N/m: 2 mm
    // lag = 0.08 N of tangential force), i.e. it slides instead of sticking.
    CHECK(r.slide_distance > 8e-3);
    CHECK(r.max_tangential_hand_force < 0.5);
    CHECK(r.contact_ticks_after_release == 0);
    CHECK(r.attractive_ticks == 0);
    CHECK(r.max_height < test::tauModel().workspaceHalfSide());  // the scenario stays in the workspace
  }
}

TEST_CASE("Random 0-3 sample command delay: the random-delay design holds the wall on the encoders") {
  // Paper 001's CoS-D condition: the command reaches the plant after d ~ U{0..3} samples, drawn each
  // period, with 4096-count encoders. The LQR designed for that delay (generalized Riccati equation,
  // input-rate weight 200) with the observer fed the torque the device reports having applied, against
  // the undelayed design on the same runs: scenario 1 at a corner and scenario 2 at the centre, 2
  // seeds each (8 runs of 3 s, kept short for the sanitizer builds).
  CommandDelayDesign random_delay;
  random_delay.samples = 3;
  random_delay.random = true;
  random_delay.rate_weight = 200.0;
  static const LqrWallDesign delay_design = designLqrWall(test::tauModel(), test::tauModel().homePose(), {}, {}, random_delay);
  const LqrWallGains& delay_gains = delay_design.gains;
  REQUIRE(delay_gains.random_command_delay);
  CHECK(delay_design.report.ms_spectral_radius < 1.0);  // mean-square stable under the random delay
  const double c = test::tauModel().workspaceHalfSide();
  double pen = 0.0, steady_told = 0.0, steady_guessed = 0.0;
  int faults_delay_aware = 0, faults_undelayed = 0;
  for (const Scenario sc : {Scenario::kStepForce, Scenario::kHand})
    for (const std::uint64_t seed : {15u, 16u}) {
      RunSpec spec;
      spec.scenario = sc;
      spec.x = sc == Scenario::kStepForce ? c : 0.0;
      spec.y = sc == Scenario::kStepForce ? -c : 0.0;
      spec.seed = seed;
      spec.max_delay_samples = 3;
      const RunMetrics aware = simulateRun(test::tauModel(), randomDelayDevice(), spec);
      faults_delay_aware += aware.fault != Fault::kNone;
      pen = std::max(pen, aware.max_penetration);
      faults_undelayed += simulateRun(test::tauModel(), undelayedDevice(), spec).fault != Fault::kNone;
      // The same run with the observer guessing the applied torque (the mean of the commands it
      // may have been) instead of being told by the board which command acted.
      spec.applied_command_reported = false;
      const RunMetrics guessed = simulateRun(test::tauModel(), randomDelayDevice(), spec);
      steady_told += aware.d_zs;
      steady_guessed += guessed.fault != Fault::kNone ? 1.0 : guessed.d_zs;
    }
  WARN("delay 0-3, 4096-count encoders: random-delay design max penetration " << pen * 1e3 << " mm; steady "
       "penetration summed over the runs " << steady_told * 1e6 << " um, " << steady_guessed * 1e6
       << " um with the applied torque guessed");
  CHECK(faults_delay_aware == 0);
  CHECK(pen < 1.1e-3);            // paper 001, CoS-D: < 1.1 mm
  CHECK(faults_undelayed == 4);   // the undelayed design loses the tool in every run
  // The device's report of the applied torque tightens the hold (measured 3.5x here; on paper
  // 001's CoS-D set-up, 180 runs, guessing puts 9 runs above 1 mm against none: README, TAU section).
  CHECK(steady_guessed > 1.3 * steady_told);
}
