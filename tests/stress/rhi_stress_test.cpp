// Stress suite, redundant planar devices (paper 003): the FME null-space controller on the 4-DoF RHI
// and on the 3-DoF example arm under random, out-of-range, non-finite, singular and near-singular
// states, extreme gains and time stamps, and long randomized interaction runs on the simulated
// linkages with an energy balance at the hand and at the actuators.
#include <catch2/catch.hpp>
#include "uhaptics/core/decompositions.hpp"  // the fixed-size SVDs, compiled once
#include <cmath>

#include "device_models.hpp"
#include "stress_support.hpp"
#include "uhaptics/backends/simulated_planar_linkage.hpp"
#include "uhaptics/renderers/fme_null_space_controller.hpp"

using namespace uhaptics;

namespace {
template <int N>
const PlanarLinkageModel<N>& model() {
  if constexpr (N == 4)
    return test::rhi4Model();
  else
    return test::planar3Model();
}

template <int N>
double inverseCondition(const Vec<N>& q) {
  Mat<2, N> J;
  model<N>().jacobian(q, J);
  if (!J.allFinite()) return 0.0;
  const Vec2 s = Eigen::JacobiSVD<Mat<2, N>>(J).singularValues();
  return s(0) > 0.0 ? s(1) / s(0) : 0.0;
}

// A configuration where every link is parallel (the Jacobian has rank 1), found by descending
// sigma_min^2 of J from a random start, then perturbed by 10^-15..10^-2 rad: singular and
// near-singular configurations without hand-deriving each device's singular set.
template <int N>
Vec<N> nearSingular(stress::AdversarialSource& src) {
  Vec<N> q;
  for (int i = 0; i < N; ++i) q(i) = src.uniform(-M_PI, M_PI);
  auto smin = [](const Vec<N>& x) {
    Mat<2, N> J;
    model<N>().jacobian(x, J);
    return Eigen::JacobiSVD<Mat<2, N>>(J).singularValues()(1);
  };
  double step = 0.2;
  for (int it = 0; it < 400 && step > 1e-14; ++it) {  // coordinate descent: no gradient needed
    bool improved = false;
    for (int i = 0; i < N; ++i)
      for (double s : {step, -step}) {
        Vec<N> t = q;
        t(i) += s;
        if (smin(t) < smin(q)) {
          q = t;
          improved = true;
        }
      }
    if (!improved) step *= 0.5;
  }
  for (int i = 0; i < N; ++i) q(i) += src.uniform(-1, 1) * src.logUniform(-15, -2);
  return q;
}

template <int N>
void judge(const FmeNullSpaceController<PlanarLinkageModel<N>>& c, Fault f, const Vec<N>& tau, stress::Tally& t) {
  const Vec<N>& limit = model<N>().effortLimits();
  ++t.cases;
  const bool within = tau.allFinite() && (tau.cwiseAbs().array() <= limit.array()).all();
  if (!within) ++t.violations;
  if (f == Fault::kNone) {
    if (c.status().alpha < 1.0 || c.status().null_space_scale < 1.0) ++t.clamped;
    return;
  }
  ++t.faults;
  if (f == Fault::kNonFiniteInput || f == Fault::kNonFiniteResult) {
    if (!tau.isZero(0.0)) ++t.violations;
  } else {
    // Singular arm or undefined cost: the documented safe answer is the primary task alone (the
    // user's force stays rendered), with no null-space torque.
    if (!c.status().tau_null.isZero(0.0) || tau != c.status().tau_primary) ++t.violations;
  }
}

template <int N>
struct StressCounts {
  stress::Tally tally;
  long option_sets = 0, refused_options = 0, singular_draws = 0;
};

template <int N>
void hammerController(std::uint64_t seed, int per_option_set, StressCounts<N>& out) {
  using Controller = FmeNullSpaceController<PlanarLinkageModel<N>>;
  const auto& m = model<N>();
  stress::AdversarialSource src(seed);
  Controller c(m, m.effortLimits(), m.homeJoints());
  for (int o = 0; o < 10; ++o) {
    typename Controller::Options opt;
    opt.beta = src.logUniform(0, 9);
    opt.damping = src.logUniform(0, 9);
    opt.mu = src.logUniform(-1, 3);
    opt.observer_shape = src.logUniform(0, 9);
    opt.transition.rho = src.logUniform(-6, 3);
    opt.transition.smooth = src.uniform(0, 1) < 0.7;
    opt.mode = static_cast<FmeEllipsoidMode>(static_cast<int>(src.uniform(0, 2.999)));
    opt.dynamically_consistent = src.uniform(0, 1) < 0.5;
    opt.gradient = src.uniform(0, 1) < 0.7 ? fme::GradientMethod::kAnalytic : fme::GradientMethod::kFiniteDifference;
    opt.motion_direction = Vec2(src.around(-1, 1), src.around(-1, 1));
    ++out.option_sets;
    if (c.setOptions(opt) != Fault::kNone) ++out.refused_options;  // old options kept: still hammered
    c.reset();
    double t = 0.0;
    Vec<N> tau;
    for (int k = 0; k < per_option_set; ++k) {
      Vec<N> q, qd;
      if (src.uniform(0, 1) < 0.25) {
        q = nearSingular<N>(src);
        ++out.singular_draws;
      } else {
        for (int i = 0; i < N; ++i) q(i) = src.around(-M_PI, M_PI);
      }
      for (int i = 0; i < N; ++i) qd(i) = src.around(-5.0, 5.0);
      const Vec2 F(src.around(-40.0, 40.0), src.around(-40.0, 40.0));
      // Time stamps: regular 1 kHz, irregular, backwards, a jump, or non-finite.
      const double u = src.uniform(0, 1);
      t += u < 0.8 ? 1e-3 : (u < 0.9 ? src.uniform(-1.0, 1.0) : (u < 0.95 ? 1e6 : src.around(0.0, 1.0)));
      if (!std::isfinite(t)) {
        const Fault f = c.tick(t, q, qd, F, tau);
        judge<N>(c, f, tau, out.tally);
        t = 0.0;
        continue;
      }
      const Fault f = c.tick(t, q, qd, F, tau);
      judge<N>(c, f, tau, out.tally);
    }
  }
}

template <int N>
void printCounts(const StressCounts<N>& s) {
  s.tally.print();
  std::cout << "stress: " << s.tally.what << ": " << s.option_sets << " option sets (" << s.refused_options
            << " refused, previous kept), " << s.singular_draws << " singular/near-singular draws\n";
}
}  // namespace

TEST_CASE("FME controller (RHI 4-DoF, 3-DoF example): random, out-of-range, non-finite, singular states, "
          "gains 1e0..1e9, irregular time stamps") {
  const int per_set = 300 * stress::scale();
  StressCounts<4> rhi;
  rhi.tally.what = "rhi4 FME null-space controller";
  StressCounts<3> planar;
  planar.tally.what = "planar3 FME null-space controller";
  hammerController<4>(20261124, per_set, rhi);
  hammerController<3>(20261125, per_set, planar);
  printCounts(rhi);
  printCounts(planar);
  CHECK(rhi.tally.violations == 0);
  CHECK(planar.tally.violations == 0);
  CHECK(rhi.tally.faults > 0);
  CHECK(rhi.tally.faults < rhi.tally.cases);
  CHECK(planar.tally.faults < planar.tally.cases);
}

TEST_CASE("FME controller: the singular-configuration search really finds rank loss") {
  // Guards the generator above: its draws must include Jacobians with sigma_min / sigma_max below
  // the controller's threshold (1e-6 on J W W J^T, i.e. ~1e-3 on J), or the singular path is untested.
  stress::AdversarialSource src(5);
  int rhi_singular = 0, planar_singular = 0;
  for (int i = 0; i < 20; ++i) {
    if (inverseCondition<4>(nearSingular<4>(src)) < 1e-3) ++rhi_singular;
    if (inverseCondition<3>(nearSingular<3>(src)) < 1e-3) ++planar_singular;
  }
  std::cout << "stress: near-singular draws with sigma_min/sigma_max < 1e-3: rhi4 " << rhi_singular
            << "/20, planar3 " << planar_singular << "/20\n";
  CHECK(rhi_singular >= 5);
  CHECK(planar_singular >= 5);
}

namespace {
// Long randomized interaction on a simulated planar linkage: a hand (spring-damper to a randomly
// moving target, evaluated at the servo rate and held over the period) drags the end effector
// around a start point and into a virtual wall (1000 N/m, normal -u, 1 cm beyond the start).
struct PlanarEnergy {
  double generated = 0.0;      // at the hand: E_to_hand + kinetic energy left [J]
  double null_work = 0.0;      // sum tau_null . dq [J]
  double primary_work = 0.0;   // sum tau_primary . dq [J]
  double positive_power_fraction = 0.0;  // ticks with qd . tau_null > 0
  double contact_time = 0.0;
  int faults = 0;
};

template <int N>
PlanarEnergy interact(const typename FmeNullSpaceController<PlanarLinkageModel<N>>::Options& opt, double seconds,
                      std::uint64_t seed) {
  using Controller = FmeNullSpaceController<PlanarLinkageModel<N>>;
  const auto& m = model<N>();
  SimulatedPlanarLinkage<N> sim(m);
  sim.reset(m.homeJoints());
  Controller c(m, m.effortLimits(), m.homeJoints(), opt);
  const double dt = 1e-3, k_wall = 1000.0, k_hand = 300.0, b_hand = 3.0;
  const Vec2 start = sim.endEffectorPosition();
  const Vec2 u(0.0, 1.0);
  const double wall = u.dot(start) + 0.01;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  double amp[2][3], freq[2][3], phase[2][3];
  for (int d = 0; d < 2; ++d)
    for (int j = 0; j < 3; ++j) {
      amp[d][j] = 0.01 * u01(rng);
      freq[d][j] = 0.2 + 1.5 * u01(rng);
      phase[d][j] = 2 * M_PI * u01(rng);
    }
  PlanarEnergy out;
  const int n = static_cast<int>(seconds / dt);
  Vec<N> tau;
  Vec2 hand = Vec2::Zero();
  Vec2 x_prev = start;
  double e_hand = 0.0;
  int positive = 0;
  for (int k = 0; k < n; ++k) {
    const double t = k * dt;
    const double envelope = std::min(1.0, std::max(0.0, seconds - 1.0 - t));  // release in the last second
    Vec2 target = start + envelope * 0.012 * (1.0 + std::sin(2 * M_PI * 0.25 * t)) * u;
    for (int d = 0; d < 2; ++d)
      for (int j = 0; j < 3; ++j) target(d) += envelope * amp[d][j] * std::sin(2 * M_PI * freq[d][j] * t + phase[d][j]);
    const Vec2 x = sim.endEffectorPosition();
    e_hand -= hand.dot(x - x_prev);
    x_prev = x;
    hand = k_hand * (target - x) - b_hand * sim.endEffectorVelocity();
    const double depth = u.dot(x) - wall;
    const Vec2 F = depth > 0.0 ? Vec2(-k_wall * depth * u) : Vec2::Zero();
    if (depth > 0.0) out.contact_time += dt;
    const Vec<N> q0 = sim.position();
    if (c.tick(t, q0, sim.velocity(), F, tau) != Fault::kNone) ++out.faults;
    if (sim.velocity().dot(c.status().tau_null) > 0.0) ++positive;
    EndEffectorLoad load;
    load.bias = hand;
    sim.setLoad(load);
    REQUIRE(sim.step(tau, dt) == Fault::kNone);
    const Vec<N> dq = sim.position() - q0;
    out.null_work += c.status().tau_null.dot(dq);
    out.primary_work += c.status().tau_primary.dot(dq);
  }
  e_hand -= hand.dot(sim.endEffectorPosition() - x_prev);
  Mat<N, N> M;
  m.massMatrix(sim.position(), M);
  out.generated = e_hand + 0.5 * sim.velocity().dot(M * sim.velocity());
  out.positive_power_fraction = static_cast<double>(positive) / n;
  return out;
}

template <int N>
void printEnergy(const char* device, const char* what, const PlanarEnergy& e) {
  std::cout << "stress: " << device << " energy, " << what << ": null-space work " << e.null_work
            << " J (power > 0 on " << 100.0 * e.positive_power_fraction << " % of ticks), primary work "
            << e.primary_work << " J, generated at the hand " << e.generated << " J, contact " << e.contact_time
            << " s, " << e.faults << " faults\n";
}

template <int N>
void energyChecks(const char* device) {
  using Options = typename FmeNullSpaceController<PlanarLinkageModel<N>>::Options;
  const double seconds = 10.0 * stress::scale();
  // (1) Damping only (beta = 0), kinematic null space: tau_N = -K_d P qd with P the orthogonal
  // projector, so the continuous power -K_d |P qd|^2 is never positive: the null-space part is
  // dissipative. The sampled version stays so while K_d T is small against the joint inertias
  // (the discrete damper's own bound); the paper's K_d = 0.1 N m s/rad is well inside it.
  Options damping_only;
  damping_only.beta = 0.0;
  damping_only.dynamically_consistent = false;
  const PlanarEnergy kin = interact<N>(damping_only, seconds, 3);
  // (2) The same with the dynamically consistent projector P = I - J^T J#^T: P is not symmetric, so
  // qd^T P qd can be negative and K_d alone guarantees nothing; reported, not judged.
  Options damping_dc = damping_only;
  damping_dc.dynamically_consistent = true;
  const PlanarEnergy dc = interact<N>(damping_dc, seconds, 3);
  // (3) The paper's controller (beta = 20, switching ellipsoids): the gradient of nu is projected
  // (no longer a potential force) and the desired ellipsoid moves with the contact, so the
  // null-space part may do positive work; reported, not judged.
  const PlanarEnergy paper = interact<N>(Options{}, seconds, 3);
  printEnergy<N>(device, "beta = 0, kinematic null space", kin);
  printEnergy<N>(device, "beta = 0, dynamically consistent", dc);
  printEnergy<N>(device, "paper's gains (beta = 20, K_d = 0.1)", paper);
  CHECK(kin.faults == 0);
  CHECK(paper.faults == 0);
  REQUIRE(kin.contact_time > 0.1 * seconds);  // the run must load the wall
  CHECK(kin.null_work < 0.0);
  CHECK(kin.positive_power_fraction == 0.0);  // instantaneous: -K_d |P qd|^2 <= 0 at every tick
}
}  // namespace

TEST_CASE("RHI energy: the null-space damping is dissipative, the full controller's figures are reported") {
  energyChecks<4>("rhi4");
}

TEST_CASE("3-DoF example energy: the null-space damping is dissipative, the full controller's figures are reported") {
  energyChecks<3>("planar3");
}
