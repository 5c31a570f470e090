// The referee against closed forms: a spring wall's depth F/k and stiffness k, a spring approached
// at constant speed (rate-hardness k), chatter at a known frequency, the energy balance of a driven
// mass-damper, and the plumbing that keeps it beside the plant (sim joint I/O, usb refused).
#include <catch2/catch.hpp>
#include <cmath>
#include <memory>

#include "uhaptics/backends/board_plant.hpp"
#include "uhaptics/backends/joint_io.hpp"
#include "uhaptics/backends/referee.hpp"
#include "uhaptics/backends/params_location.hpp"
#include "uhaptics/core/fault.hpp"
#include "uhaptics/tools/alloc_probe.hpp"

using uhaptics::PlantTruth;
using uhaptics::Referee;
using uhaptics::RefereeReport;
using uhaptics::RefereeSample;
using uhaptics::Vec3;

namespace {

constexpr double kPeriod = 1e-3;  // [s] the servo period every test samples at

// A point mass on z against a spring wall at z = 0 (an ideal device: it applies what the scene asks,
// k depth upward), pushed down by a user with a constant force and a damper of its own. Semi-implicit
// Euler in 100 substeps a period, the user's force held over the period (as a plant holds it).
struct WallRig {
  double mass = 0.1, stiffness = 2000.0, push = 5.0, user_damping = 0.0;
  double ripple_amplitude = 0.0, ripple_hz = 0.0;  // added to the applied force only (chatter)
  double z = 0.0, v = 0.0, t = 0.0;

  RefereeReport run(double seconds) {
    Referee referee;
    const int substeps = 100;
    const double h = kPeriod / substeps;
    RefereeSample start;  // the state before the first period: where the tool touches the surface
    start.dt = kPeriod;
    start.truth.position = Vec3(0, 0, z);
    referee.observe(start);
    for (long k = 0; k < std::lround(seconds / kPeriod); ++k) {
      const double user = -push - user_damping * v;  // held over the period
      for (int s = 0; s < substeps; ++s) {
        const double wall = z < 0.0 ? -stiffness * z : 0.0;
        v += h * (user + wall) / mass;
        z += h * v;
      }
      t += kPeriod;
      const double wall = z < 0.0 ? -stiffness * z : 0.0;
      RefereeSample sample;
      sample.dt = kPeriod;
      sample.truth.position = Vec3(0, 0, z);
      sample.truth.velocity = Vec3(0, 0, v);
      sample.truth.user_force = Vec3(0, 0, user);
      sample.truth.applied_force = Vec3(0, 0, wall + ripple_amplitude * std::sin(2 * M_PI * ripple_hz * t));
      sample.asked_force = Vec3(0, 0, wall);
      referee.observe(sample);
    }
    return referee.report();
  }
};

}  // namespace

TEST_CASE("referee: a spring wall pushed with F holds F / k deep and renders k", "[backends][referee]") {
  WallRig rig;
  rig.user_damping = 2.0 * std::sqrt(rig.stiffness * rig.mass);  // critically damped: no overshoot
  const RefereeReport r = rig.run(2.0);
  const double depth_mm = 1e3 * rig.push / rig.stiffness;  // 2.5 mm
  CHECK(r.contacts == 1);
  CHECK(r.max_true_penetration_mm == Approx(depth_mm).epsilon(0.005));
  CHECK(r.rendered_stiffness_N_per_m == Approx(rig.stiffness).epsilon(0.005));
  CHECK(r.hold_samples > 1000);
  CHECK(r.force_error_rms_N == Approx(0.0).margin(1e-12));  // the ideal device applies what is asked
  CHECK(r.chatter_N < 0.002 * rig.push);  // the settling's tail: a smooth hold has no buzz
  CHECK(r.saturated_share == 0.0);
  CHECK(r.peak_user_force_N == Approx(rig.push).epsilon(0.05));
  // The wall is passive and the user's damper takes energy: the device gave the user nothing back
  // beyond what the spring still stores, 1/2 F^2 / k = 6.25 mJ.
  CHECK(r.generated_energy_mJ <= 0.0);
}

TEST_CASE("referee: a stiffer wall under the same push is shallower and stiffer, in proportion",
          "[backends][referee]") {
  WallRig soft, stiff;
  stiff.stiffness = 4.0 * soft.stiffness;
  soft.user_damping = 2.0 * std::sqrt(soft.stiffness * soft.mass);
  stiff.user_damping = 2.0 * std::sqrt(stiff.stiffness * stiff.mass);
  const RefereeReport a = soft.run(2.0), b = stiff.run(2.0);
  CHECK(b.max_true_penetration_mm == Approx(a.max_true_penetration_mm / 4.0).epsilon(0.005));
  CHECK(b.rendered_stiffness_N_per_m == Approx(4.0 * a.rendered_stiffness_N_per_m).epsilon(0.005));
}

TEST_CASE("referee: approached at constant speed a spring wall's rate-hardness is k", "[backends][referee]") {
  Referee referee;
  const double k = 3000.0, speed = 0.05;  // N/m, m/s
  for (int i = 0; i < 100; ++i) {
    const double z = 0.002 - speed * kPeriod * i;  // from 2 mm above, down through the surface
    const double force = z < 0.0 ? -k * z : 0.0;
    RefereeSample s;
    s.dt = kPeriod;
    s.truth.position = Vec3(0, 0, z);
    s.truth.velocity = Vec3(0, 0, -speed);
    s.truth.applied_force = Vec3(0, 0, force);
    s.asked_force = Vec3(0, 0, force);
    referee.observe(s);
  }
  const RefereeReport r = referee.report();
  CHECK(r.contacts == 1);
  CHECK(r.onset_samples == 1);
  CHECK(r.rate_hardness_N_per_m == Approx(k).epsilon(1e-9));
  CHECK(r.hold_samples == 0);  // always moving: no hold, no stiffness
  CHECK(std::isnan(r.rendered_stiffness_N_per_m));
}

TEST_CASE("referee: a slide round a curve leaves the entry plane's depth alone", "[backends][referee]") {
  // The tool enters a sphere of radius 5 mm at its top and slides round it at 0.1 mm depth: the scene's
  // force turns with it. Along the entry normal the slide would read as up to 5 mm deep; within 30 deg
  // of it, the depth is 0.1 mm, and the 60 deg beyond are counted as turned.
  Referee referee;
  const double radius = 0.005, depth = 1e-4, k = 2000.0;
  RefereeSample s;
  s.dt = kPeriod;
  s.truth.position = Vec3(0, 0, radius + 1e-4);
  referee.observe(s);  // just above the top
  for (int i = 0; i <= 90; ++i) {
    const double a = i * M_PI / 180.0;
    const Vec3 n(std::sin(a), 0.0, std::cos(a));
    s.truth.position = (radius - depth) * n;
    s.truth.velocity = Vec3::Zero();
    s.asked_force = k * depth * n;
    s.truth.applied_force = s.asked_force;
    referee.observe(s);
  }
  const RefereeReport r = referee.report();
  CHECK(r.contacts == 1);
  // The entry plane is through the last point above (0.1 mm over the top); at 30 deg, the last turn
  // the plane counts, the tool is 0.1 mm + r - (r - 0.1 mm) cos 30 below it.
  CHECK(r.max_true_penetration_mm ==
        Approx(1e3 * (radius + 1e-4 - (radius - depth) * std::cos(M_PI / 6))).margin(1e-6));
  CHECK(r.turned_samples == 60);
}

TEST_CASE("referee: chatter is the force content above 30 Hz during holds", "[backends][referee]") {
  WallRig rig;
  rig.user_damping = 2.0 * std::sqrt(rig.stiffness * rig.mass);
  rig.ripple_amplitude = 0.4;  // N at 100 Hz: passes the 30 Hz high-pass (gain 0.995)
  rig.ripple_hz = 100.0;
  const RefereeReport r = rig.run(2.0);
  CHECK(r.chatter_N == Approx(0.4 / std::sqrt(2.0)).epsilon(0.03));
  // A 5 Hz ripple is below the cutoff: (5/30)^2 of it passes.
  WallRig slow = rig;
  slow.ripple_hz = 5.0;
  slow.z = slow.v = slow.t = 0.0;
  CHECK(slow.run(2.0).chatter_N < 0.03 * 0.4);
}

TEST_CASE("referee: the energy a driven mass-damper takes from its user, in closed form", "[backends][referee]") {
  // m x'' + b x' = F0 sin(w t), started in its steady state: over whole cycles the user puts in
  // b |V|^2 / 2 per second with |V| = F0 / |b + i m w|, all of it dissipated; the device gives the
  // user minus that.
  const double m = 0.2, b = 2.0, f0 = 2.0, w = 4.0 * M_PI;  // 2 Hz
  const double c = b * b + m * m * w * w;
  // Steady state: x = A sin(w t) + B cos(w t), with v = w (A cos - B sin).
  const double A = -f0 * m * w * w / (w * w * c), B = -f0 * b * w / (w * w * c);
  double x = B, v = w * A, t = 0.0;
  Referee referee;
  const int substeps = 200;
  const double h = kPeriod / substeps;
  const double seconds = 2.0;  // four cycles
  for (long k = 0; k < std::lround(seconds / kPeriod); ++k) {
    // The user's force at the middle of the period, held over it (a zero-order hold centred on the
    // sine, so the held force has the sine's phase).
    const double force = f0 * std::sin(w * (t + 0.5 * kPeriod));
    for (int s = 0; s < substeps; ++s) {
      v += h * (force - b * v) / m;
      x += h * v;
    }
    t += kPeriod;
    RefereeSample sample;
    sample.dt = kPeriod;
    sample.truth.position = Vec3(x, 0, 0);
    sample.truth.velocity = Vec3(v, 0, 0);
    sample.truth.user_force = Vec3(force, 0, 0);
    referee.observe(sample);
  }
  const double expected_mJ = -1e3 * seconds * f0 * f0 * b / (2.0 * c);  // about -775 mJ
  const RefereeReport r = referee.report();
  CHECK(r.contacts == 0);
  CHECK(std::isnan(r.force_error_rms_N));
  // The first sample's displacement is not counted (the referee has no position before it).
  CHECK(r.generated_energy_mJ == Approx(expected_mJ).epsilon(0.01));
}

TEST_CASE("referee: non-finite samples are skipped, observe allocates nothing", "[backends][referee]") {
  Referee referee;
  RefereeSample s;
  s.dt = kPeriod;
  s.truth.position = Vec3(0, 0, std::nan(""));
  referee.observe(s);
  s.truth.position = Vec3::Zero();
  s.dt = -1.0;
  referee.observe(s);
  CHECK(referee.report().samples == 0);
  s.dt = kPeriod;
  s.asked_force = Vec3(0, 0, 1.0);
  const std::uint64_t before = uhaptics::tools::threadAllocationCount();
  for (int i = 0; i < 100; ++i) referee.observe(s);
  CHECK(uhaptics::tools::threadAllocationCount() - before == 0);
  CHECK(referee.report().samples == 100);
  CHECK(referee.report().contacts == 1);
}

TEST_CASE("referee: bad options are refused by name", "[backends][referee]") {
  uhaptics::RefereeOptions o;
  o.hold_speed = 0.0;
  CHECK_THROWS_WITH(Referee(o), Catch::Contains("hold_speed"));
  o = {};
  o.chatter_cutoff_hz = std::nan("");
  CHECK_THROWS_WITH(Referee(o), Catch::Contains("chatter_cutoff_hz"));
}

namespace {
// A plant that states its truth: a point the caller's user force moves (unit mass, no actuators'
// force at the point), for the plumbing test.
class TruthPlant final : public uhaptics::BoardPlant {
 public:
  int jointCount() const noexcept override { return 1; }
  int actuatorCount() const noexcept override { return 1; }
  void readJoints(double* positions) noexcept override { positions[0] = z_; }
  void applyCommand(const double* efforts) noexcept override { effort_ = efforts[0]; }
  void advance(double dt) noexcept override {
    v_ += dt * (user_ + effort_);
    z_ += dt * v_;
  }
  void setUserForce(const Vec3& force) noexcept override { user_ = force.z(); }
  bool readTruth(PlantTruth& t) noexcept override {
    t.position = Vec3(0, 0, z_);
    t.velocity = Vec3(0, 0, v_);
    t.user_force = Vec3(0, 0, user_);
    t.applied_force = Vec3(0, 0, effort_);
    return true;
  }

 private:
  double z_ = 0.0, v_ = 0.0, user_ = 0.0, effort_ = 0.0;
};
}  // namespace

TEST_CASE("referee: the sim joint I/O referees each session's plant and keeps the last report",
          "[backends][referee]") {
  uhaptics::BoardSpec spec;
  spec.descriptor.name = "truth plant";
  spec.descriptor.joints = 1;
  spec.descriptor.actuators = 1;
  spec.descriptor.effort_limit[0] = 10.0;
  auto channel = std::make_shared<uhaptics::RefereeChannel>();
  auto io = uhaptics::makeSimJointIo(spec, [] { return std::make_unique<TruthPlant>(); }, channel);
  io->open();
  // The user pushes the point down 1 N; the "scene" asks 2 N up, which the device applies: the
  // point goes up against the user, and the device has given the user energy.
  const double up = 2.0;
  for (int i = 0; i < 500; ++i) {
    io->command(&up);
    io->setUserForce(Vec3(0, 0, -1.0));
    io->setSceneForce(Vec3(0, 0, up));
    io->advance(kPeriod);
  }
  RefereeReport r = channel->latest();
  CHECK(r.samples == 500);
  CHECK(r.contacts == 1);
  // x = t^2 / 2 at 1 m/s^2 over 0.5 s: 125 mm up; the user's -1 N over it is +125 mJ to the user.
  CHECK(r.generated_energy_mJ == Approx(125.0).epsilon(0.01));
  io->close();
  CHECK(channel->latest().samples == 500);  // the last session's figures stay
  io->open();
  CHECK(channel->latest().samples == 0);  // a new session speaks of itself
  io->close();
}

TEST_CASE("referee: usb has no truth to judge by", "[backends][referee]") {
  uhaptics::JointIoOptions options;
  options.params_dir = uhaptics::defaultParamsDirectory();
  options.referee = std::make_shared<uhaptics::RefereeChannel>();
  CHECK_THROWS_WITH(uhaptics::makeJointIo("tau", "usb", options), Catch::Contains("referee"));
}
