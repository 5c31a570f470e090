#include "uhaptics/core/passivity_controller.hpp"

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <limits>
#include <iterator>
#include <random>

#include "uhaptics/core/passivity_observer.hpp"
#include "uhaptics/tools/alloc_probe.hpp"

using uhaptics::Fault;
using uhaptics::PassivityController;
using uhaptics::PassivityControllerOptions;
using V1 = Eigen::Matrix<double, 1, 1>;

namespace {

template <int N = 1>
PassivityControllerOptions<N> withCap(double max_damping, double min_rate = 1e-3) {
  PassivityControllerOptions<N> o;
  o.max_damping = max_damping;
  o.min_rate = min_rate;
  return o;
}

// A 1-DoF joint (inertia J, viscous friction b, Coulomb friction fc) that a force-driven hand
// pushes with a constant torque toward a virtual wall at q = 0, rendered at T = 1 ms as -K q from
// the position sampled at the start of each period and held (what a servo does). K T / 2 = 4.5 b:
// far beyond Colgate's bound b > K T / 2, so the sampled wall alone goes active. The plant is
// integrated with 20 substeps per period; the rate is the backward difference of the measured
// positions. The scene is scaled so that one period of wall work stays well under 1 mJ: the
// controller acts one period after the energy shows, so E_out can exceed zero by about that much.
//
// encoder: positions quantized to 4096 counts per turn, and the joint carries Coulomb friction
// above K count / 2 (Abbott and Okamura, IEEE WHC 2005: the condition for a quantized wall to be
// passive). Without it the joint settles into a chatter below one count, which the quantized
// observer reads as K count^2 / 2 of generated energy per count flip whatever the true work is.
struct WallRun {
  double peak_observed = 0.0;    // largest E_out the controller's observer reported [J]
  double peak_true = 0.0;        // largest true work of the applied command [J] (unquantized q)
  double first_amplitude = 0.0;  // max |q - q_rest| over the first contact, 0.05 s [rad]
  double last_amplitude = 0.0;   // max |q - q_rest| over the last 0.5 s [rad]
  std::uint64_t active_ticks = 0;
  std::uint64_t faults = 0;
};

constexpr double kT = 1e-3;
constexpr double kJ = 5e-5, kB = 5e-4, kK = 4.5, kHand = 0.045, kGap = 0.01;
constexpr double kMaxDamping = 0.01;  // N m s/rad: 0.2 J / T, well inside what the servo renders
const double kCount = 2.0 * M_PI / 4096.0;

WallRun runWall(bool controller, bool encoder) {
  constexpr int kSub = 20, kTicks = 3000;
  const double h = kT / kSub;
  const double fc = encoder ? 4e-3 : 0.0;
  PassivityControllerOptions<1> o = withCap(kMaxDamping, encoder ? 0.5 * kCount / kT : 1e-3);
  o.enabled = controller;
  PassivityController<1> pc(o);

  const double q_rest = kHand / kK;
  double q = -kGap, v = 0.0, measured_prev = 0.0;
  double true_work = 0.0, q_prev = q, u_prev = 0.0;
  WallRun run;
  V1 out;
  for (int k = 0; k < kTicks; ++k) {
    const double measured = encoder ? std::floor(q / kCount) * kCount : q;
    const double rate = k == 0 ? 0.0 : (measured - measured_prev) / kT;
    measured_prev = measured;
    const double wall = measured > 0.0 ? -kK * measured : 0.0;
    if (pc.update(V1(measured), V1(rate), V1(wall), kT, out) != Fault::kNone) ++run.faults;

    true_work += u_prev * (q - q_prev);
    run.peak_true = std::max(run.peak_true, true_work);
    q_prev = q;
    u_prev = out(0);

    const double torque = out(0) + kHand;
    for (int s = 0; s < kSub; ++s) {  // semi-implicit Euler; Coulomb friction sticks at v = 0
      double f = torque - kB * v;
      if (v != 0.0) f -= std::copysign(fc, v);
      else f = std::abs(torque) <= fc ? 0.0 : f - std::copysign(fc, torque);
      double v_next = v + h * f / kJ;
      if (fc > 0.0 && v != 0.0 && v_next * v < 0.0) v_next = 0.0;
      v = v_next;
      q += h * v;
    }
    const double deviation = std::abs(q - q_rest);
    if (k < 50) run.first_amplitude = std::max(run.first_amplitude, deviation);
    if (k >= kTicks - 500) run.last_amplitude = std::max(run.last_amplitude, deviation);
  }
  run.peak_observed = pc.peakEnergyOut();
  run.active_ticks = pc.activeTicks();
  return run;
}

}  // namespace

TEST_CASE("passivity controller: the damping takes out the observed excess in one period") {
  const double T = 1e-3, u0 = 2.0, step = 0.01, qd = 0.5;
  PassivityController<1> pc(withCap(1e3));
  V1 out;
  REQUIRE(pc.update(V1(0.0), V1(step / T), V1(u0), T, out) == Fault::kNone);
  CHECK(out(0) == u0);  // nothing observed yet
  // The period closes with the joint moved along u0: E_out = u0 step generated.
  REQUIRE(pc.update(V1(step), V1(qd), V1(0.0), T, out) == Fault::kNone);
  const double energy = u0 * step;
  const double alpha = energy / (T * qd * qd);
  CHECK(pc.energyOut() == Approx(energy).epsilon(1e-12));
  CHECK(pc.lastDamping()(0) == Approx(alpha).epsilon(1e-12));
  CHECK(out(0) == Approx(-alpha * qd).epsilon(1e-12));
  CHECK(pc.activeTicks() == 1);
  // The joint keeps its rate over the next period: the damping does exactly -E of work.
  REQUIRE(pc.update(V1(step + qd * T), V1(qd), V1(0.0), T, out) == Fault::kNone);
  CHECK(pc.dissipated() == Approx(energy).epsilon(1e-12));
  CHECK(std::abs(pc.energyOut()) <= 1e-12 * energy);
}

TEST_CASE("passivity controller: a sampled wall beyond the Colgate bound goes active without it") {
  REQUIRE(kK * kT / 2.0 > 4.0 * kB);
  for (const bool encoder : {false, true}) {
    INFO("encoder " << encoder);
    const WallRun run = runWall(false, encoder);
    CHECK(run.peak_observed > 0.05);                         // 50 times the bound the controller keeps
    CHECK(run.last_amplitude > 2.0 * run.first_amplitude);  // the contact oscillation grows
    CHECK(run.active_ticks == 0);
    CHECK(run.faults == 0);
  }
}

TEST_CASE("passivity controller: keeps the sampled wall from generating more than 1 mJ") {
  for (const bool encoder : {false, true}) {
    INFO("encoder " << encoder);
    const WallRun run = runWall(true, encoder);
    CHECK(run.peak_observed <= 1e-3);
    CHECK(run.peak_true <= 1e-3);
    CHECK(run.last_amplitude < 0.2 * run.first_amplitude);  // the contact oscillation decays
    CHECK(run.active_ticks > 0);
    CHECK(run.faults == 0);
  }
}

TEST_CASE("passivity controller: no damping at zero or sub-threshold rate") {
  PassivityController<2> pc(withCap<2>(10.0, 0.01));
  Eigen::Vector2d out;
  pc.update(Eigen::Vector2d(0, 0), Eigen::Vector2d(0, 0), Eigen::Vector2d(3, -1), 1e-3, out);
  REQUIRE(pc.update(Eigen::Vector2d(0.1, 0), Eigen::Vector2d::Zero(), Eigen::Vector2d(0.5, 0.25), 1e-3, out) ==
          Fault::kNone);
  REQUIRE(pc.energyOut() > 0.0);
  CHECK(out == Eigen::Vector2d(0.5, 0.25));
  CHECK(pc.lastDamping().isZero());
  CHECK(pc.activeTicks() == 0);

  // Joint 0 under the guard, joint 1 above it: only joint 1 is damped, and |qd|^2 counts it alone.
  const double e = pc.energyOut();
  pc.update(Eigen::Vector2d(0.1, 0), Eigen::Vector2d(0.005, 2.0), Eigen::Vector2d(0, 0), 1e-3, out);
  CHECK(pc.lastDamping()(0) == 0.0);
  CHECK(pc.lastDamping()(1) == Approx(std::min(10.0, e / (1e-3 * 4.0))).epsilon(1e-12));
  CHECK(out(0) == 0.0);
}

TEST_CASE("passivity controller: a million ticks of extreme inputs never give a non-finite command") {
  const double inf = std::numeric_limits<double>::infinity();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double specials[] = {0.0,   -0.0,  std::numeric_limits<double>::denorm_min(), -1e-310, 1e-300, 1e300,
                             -1e300, std::numeric_limits<double>::max(), -std::numeric_limits<double>::max(),
                             1e-8,  inf,   nan};
  std::mt19937_64 rng(20020101);
  std::uniform_real_distribution<double> uniform(-10.0, 10.0);
  std::uniform_int_distribution<int> pick(0, 3 * static_cast<int>(std::size(specials)));
  const auto draw = [&] {
    const int i = pick(rng);
    return i < static_cast<int>(std::size(specials)) ? specials[i] : uniform(rng);
  };
  PassivityController<3> pc(withCap<3>(5.0, 0.0));
  Eigen::Vector3d q, qd, u, out;
  std::uint64_t non_finite = 0, over_cap = 0, bad_energy = 0;
  for (int k = 0; k < 1000000; ++k) {
    for (int j = 0; j < 3; ++j) {
      q(j) = draw();
      qd(j) = draw();
      u(j) = draw();
    }
    const double period = k % 7 == 0 ? draw() : 1e-3;
    pc.update(q, qd, u, period, out);
    non_finite += !out.allFinite();
    over_cap += (pc.lastDamping().array() > 5.0).any() || (pc.lastDamping().array() < 0.0).any();
    bad_energy += !std::isfinite(pc.energyOut()) || !std::isfinite(pc.dissipated());
  }
  CHECK(non_finite == 0);
  CHECK(over_cap == 0);
  CHECK(bad_energy == 0);
  CHECK(pc.faults() > 0);
  CHECK(pc.activeTicks() > 0);
}

TEST_CASE("passivity controller: the cap bounds the damping and the rest of the energy is carried") {
  const double T = 1e-3, cap = 2.0, qd = 0.5;
  PassivityController<1> pc(withCap(cap));
  V1 out;
  pc.update(V1(0.0), V1(0.0), V1(1.0), T, out);
  pc.update(V1(0.01), V1(qd), V1(0.0), T, out);  // E_out = 0.01 J: needs alpha = 40 > cap
  const double energy = 0.01;
  CHECK(pc.lastDamping()(0) == cap);
  CHECK(out(0) == -cap * qd);
  // One period at the same rate takes out cap qd^2 T; the rest stays on the observer.
  const double residual = energy - cap * qd * qd * T;
  pc.update(V1(0.01 + qd * T), V1(qd), V1(0.0), T, out);
  CHECK(pc.energyOut() == Approx(residual).epsilon(1e-12));
  CHECK(pc.dissipated() == Approx(cap * qd * qd * T).epsilon(1e-12));
  CHECK(pc.lastDamping()(0) == cap);  // still over the cap: acts on the carried energy
  CHECK(pc.activeTicks() == 2);

  // Per-joint caps clip a shared alpha joint by joint.
  PassivityControllerOptions<2> o = withCap<2>(0.0);
  o.max_damping_per_joint = Eigen::Vector2d(1.0, 1e3);
  PassivityController<2> pc2(o);
  Eigen::Vector2d out2;
  pc2.update(Eigen::Vector2d(0, 0), Eigen::Vector2d(0, 0), Eigen::Vector2d(1, 0), T, out2);
  pc2.update(Eigen::Vector2d(0.01, 0), Eigen::Vector2d(1, 1), Eigen::Vector2d(0, 0), T, out2);
  const double shared = 0.01 / (T * 2.0);  // 5 N m s/rad: above joint 0's cap, below joint 1's
  CHECK(pc2.lastDamping()(0) == 1.0);
  CHECK(pc2.lastDamping()(1) == Approx(shared).epsilon(1e-12));
}

TEST_CASE("passivity controller: non-finite input gives a zero command and counts a fault") {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  PassivityController<2> pc(withCap<2>(10.0));
  const Eigen::Vector2d q(0.1, 0.2), qd(0.5, -0.5), u(1.0, 2.0);
  Eigen::Vector2d out;
  REQUIRE(pc.update(q, qd, u, 1e-3, out) == Fault::kNone);
  CHECK(pc.update(Eigen::Vector2d(nan, 0), qd, u, 1e-3, out) == Fault::kNonFiniteInput);
  CHECK(out.isZero());
  CHECK(pc.update(q, Eigen::Vector2d(0, inf), u, 1e-3, out) == Fault::kNonFiniteInput);
  CHECK(out.isZero());
  CHECK(pc.update(q, qd, Eigen::Vector2d(-inf, 0), 1e-3, out) == Fault::kNonFiniteInput);
  CHECK(out.isZero());
  CHECK(pc.update(q, qd, u, nan, out) == Fault::kNonFiniteInput);
  CHECK(pc.update(q, qd, u, 0.0, out) == Fault::kInvalidParameter);
  CHECK(pc.update(q, qd, u, -1e-3, out) == Fault::kInvalidParameter);
  CHECK(out.isZero());
  CHECK(pc.faults() == 6);
  CHECK(pc.lastFault() == Fault::kInvalidParameter);
  CHECK(std::isfinite(pc.energyOut()));
  // Valid input again: a command, and the zero commands did no work.
  CHECK(pc.update(q, qd, u, 1e-3, out) == Fault::kNone);
  CHECK(out == u);
  CHECK(pc.lastFault() == Fault::kNone);
  CHECK(pc.energyOut() == 0.0);
}

TEST_CASE("passivity controller: disabled it passes the command through and still observes") {
  PassivityControllerOptions<2> o = withCap<2>(10.0);
  o.enabled = false;
  PassivityController<2> pc(o);
  uhaptics::PassivityObserver<2> reference;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  Eigen::Vector2d q = Eigen::Vector2d::Zero(), out;
  bool identical = true;
  for (int k = 0; k < 2000; ++k) {
    const Eigen::Vector2d u(uniform(rng), uniform(rng)), qd(uniform(rng), uniform(rng));
    pc.update(q, qd, u, 1e-3, out);
    identical = identical && std::memcmp(out.data(), u.data(), sizeof(double) * 2) == 0;
    reference.update(q, u);
    q += 1e-3 * (u + Eigen::Vector2d(uniform(rng), uniform(rng)));  // moves along u on average
  }
  CHECK(identical);
  CHECK(pc.activeTicks() == 0);
  CHECK(pc.dissipated() == 0.0);
  CHECK(pc.energyOut() > 0.0);
  CHECK(pc.energyOut() == Approx(reference.energyOut()).epsilon(1e-12));
  CHECK(pc.peakEnergyOut() == Approx(reference.peakEnergyOut()).epsilon(1e-12));
  // Switched on, the same controller damps the excess it observed while off.
  pc.setEnabled(true);
  pc.update(q, Eigen::Vector2d(1, 1), Eigen::Vector2d::Zero(), 1e-3, out);
  CHECK(pc.activeTicks() == 1);
}

TEST_CASE("passivity controller: the energy threshold is tolerated and only the rest is damped") {
  PassivityControllerOptions<1> o = withCap(1e3);
  o.energy_threshold = 0.004;
  PassivityController<1> pc(o);
  V1 out;
  pc.update(V1(0.0), V1(0.0), V1(1.0), 1e-3, out);
  pc.update(V1(0.003), V1(1.0), V1(0.0), 1e-3, out);  // 3 mJ: under the threshold
  CHECK(pc.lastDamping()(0) == 0.0);
  pc.update(V1(0.003), V1(1.0), V1(1.0), 1e-3, out);
  pc.update(V1(0.009), V1(2.0), V1(0.0), 1e-3, out);  // 9 mJ: 5 mJ above it
  CHECK(pc.lastDamping()(0) == Approx(0.005 / (1e-3 * 4.0)).epsilon(1e-12));
}

TEST_CASE("passivity controller: a dynamic joint count matches the fixed one") {
  PassivityControllerOptions<Eigen::Dynamic> od;
  od.max_damping = 3.0;
  PassivityController<Eigen::Dynamic> dynamic(od, 3);
  PassivityController<3> fixed(withCap<3>(3.0));
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  Eigen::Vector3d q = Eigen::Vector3d::Zero(), out;
  PassivityController<Eigen::Dynamic>::Vector out_d;
  double worst = 0.0;
  for (int k = 0; k < 500; ++k) {
    const Eigen::Vector3d u(uniform(rng), uniform(rng), uniform(rng));
    const Eigen::Vector3d qd = u + 0.1 * Eigen::Vector3d(uniform(rng), uniform(rng), uniform(rng));
    fixed.update(q, qd, u, 1e-3, out);
    dynamic.update(q, qd, u, 1e-3, out_d);
    worst = std::max(worst, (out - out_d).cwiseAbs().maxCoeff());
    q += 1e-3 * qd;
  }
  CHECK(worst <= 1e-12);
  CHECK(dynamic.activeTicks() == fixed.activeTicks());
  CHECK(fixed.activeTicks() > 0);
  CHECK(dynamic.energyOut() == Approx(fixed.energyOut()).epsilon(1e-12));
  // A size other than dim() is refused.
  CHECK(dynamic.update(Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero(), 1e-3, out_d) ==
        Fault::kInvalidParameter);
  CHECK(out_d.size() == 3);
  CHECK(out_d.isZero());
}

TEST_CASE("passivity controller: out-of-range options are refused at construction") {
  using Dyn = PassivityController<Eigen::Dynamic>;
  PassivityControllerOptions<Eigen::Dynamic> od;
  CHECK_THROWS_AS(Dyn(od, 0), uhaptics::Error);
  CHECK_THROWS_AS(Dyn(od, Dyn::kMaxDim + 1), uhaptics::Error);
  od.max_damping_per_joint = Eigen::Vector2d(1, 1);
  CHECK_THROWS_AS(Dyn(od, 3), uhaptics::Error);
  CHECK_NOTHROW(Dyn(od, 2));
  CHECK_THROWS_AS(PassivityController<2>(withCap<2>(-1.0)), uhaptics::Error);
  CHECK_THROWS_AS(PassivityController<2>(withCap<2>(std::numeric_limits<double>::infinity())), uhaptics::Error);
  CHECK_THROWS_AS(PassivityController<2>(withCap<2>(1.0, std::nan(""))), uhaptics::Error);
  PassivityControllerOptions<2> o = withCap<2>(1.0);
  o.energy_threshold = -1e-3;
  CHECK_THROWS_AS(PassivityController<2>(o), uhaptics::Error);
  o.energy_threshold = 0.0;
  o.max_damping_per_joint = Eigen::Vector2d(1.0, -1.0);
  CHECK_THROWS_AS(PassivityController<2>(o), uhaptics::Error);
}

TEST_CASE("passivity controller: a servo tick allocates nothing") {
  PassivityController<6> pc(withCap<6>(1.0));
  PassivityControllerOptions<Eigen::Dynamic> od;
  od.max_damping = 1.0;
  PassivityController<Eigen::Dynamic> dynamic(od, 4);
  Eigen::Matrix<double, 6, 1> q = Eigen::Matrix<double, 6, 1>::Zero(), out;
  PassivityController<Eigen::Dynamic>::Vector out_d(4);
  const Eigen::Matrix<double, 6, 1> u = Eigen::Matrix<double, 6, 1>::LinSpaced(6, -1.0, 1.0);
  uhaptics::tools::AllocationScope scope;
  for (int k = 0; k < 1000; ++k) {
    pc.update(q, u, u, 1e-3, out);
    dynamic.update(q.head<4>(), u.head<4>(), u.head<4>(), 1e-3, out_d);
    q += 1e-3 * u;
  }
  const std::uint64_t allocations = scope.count();
  CHECK(allocations == 0);
  CHECK(pc.activeTicks() > 0);
  CHECK(dynamic.activeTicks() > 0);
}

TEST_CASE("passivity controller: effort limits hold the command and the observer counts the held one") {
  const double T = 1e-3, limit = 1.5, qd = 0.5;
  PassivityControllerOptions<1> o = withCap(1e3);
  o.effort_limit = V1(limit);
  PassivityController<1> pc(o);
  V1 out;
  // The renderer's effort above the limit is held to it, and its work is the held effort's.
  REQUIRE(pc.update(V1(0.0), V1(0.0), V1(4.0), T, out) == Fault::kNone);
  CHECK(out(0) == limit);
  REQUIRE(pc.update(V1(0.01), V1(qd), V1(1.4), T, out) == Fault::kNone);
  CHECK(pc.energyOut() == Approx(limit * 0.01).epsilon(1e-12));
  // The damping wanted here (15 mJ in one period at 0.5 rad/s) would take the command far below
  // -limit: the device gets -limit, and only the damping that survived the hold dissipates.
  CHECK(pc.lastDamping()(0) > 0.0);
  CHECK(out(0) == -limit);
  const double applied_brake = 1.4 + limit;
  REQUIRE(pc.update(V1(0.01 + qd * T), V1(qd), V1(1.4), T, out) == Fault::kNone);
  CHECK(pc.dissipated() == Approx(applied_brake * qd * T).epsilon(1e-12));
  CHECK(pc.energyOut() == Approx(limit * 0.01 - limit * qd * T).epsilon(1e-12));
  CHECK(std::abs(out(0)) <= limit);

  // Disabled, the command passes through unchanged, limits included.
  o.enabled = false;
  PassivityController<1> off(o);
  REQUIRE(off.update(V1(0.0), V1(0.0), V1(4.0), T, out) == Fault::kNone);
  CHECK(out(0) == 4.0);

  // Limits of the wrong size or not positive are refused.
  PassivityControllerOptions<2> o2 = withCap<2>(1.0);
  o2.effort_limit = V1(1.0);
  CHECK_THROWS_AS(PassivityController<2>(o2), uhaptics::Error);
  o2.effort_limit = Eigen::Vector2d(1.0, 0.0);
  CHECK_THROWS_AS(PassivityController<2>(o2), uhaptics::Error);
  o2.effort_limit = Eigen::Vector2d(1.0, std::nan(""));
  CHECK_THROWS_AS(PassivityController<2>(o2), uhaptics::Error);
  o2.effort_limit = Eigen::Vector2d(1.0, std::numeric_limits<double>::infinity());
  CHECK_NOTHROW(PassivityController<2>(o2));
}

TEST_CASE("passivity controller: an interrupted chain does not count the work across the gap") {
  const double T = 1e-3;
  PassivityController<1> pc(withCap(0.0));  // observe only
  V1 out;
  pc.update(V1(0.0), V1(0.0), V1(2.0), T, out);
  pc.update(V1(0.01), V1(0.0), V1(2.0), T, out);
  const double before = pc.energyOut();
  CHECK(before == Approx(0.02).epsilon(1e-12));
  // Another stage commanded the gap: the joint moves a lot, none of it is this command's work.
  pc.interrupt();
  pc.update(V1(0.5), V1(0.0), V1(1.0), T, out);
  CHECK(pc.energyOut() == before);
  CHECK(pc.peakEnergyOut() == Approx(0.02).epsilon(1e-12));
  pc.update(V1(0.51), V1(0.0), V1(0.0), T, out);
  CHECK(pc.energyOut() == Approx(before + 0.01).epsilon(1e-12));
  CHECK(pc.faults() == 0);
}
