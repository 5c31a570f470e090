#include <catch2/catch.hpp>
#include <algorithm>
#include <limits>
#include <random>

#include "rhi_fixtures.hpp"
#include "uhaptics/experiments/rhi_experiments.hpp"
#include "uhaptics/tools/alloc_probe.hpp"

using namespace uhaptics;

namespace {
using rhi_test::randomConfiguration;
using rhi_test::rhi4;
using rhi_test::rhi4Product;
bool withinLimits(const Vec<4>& tau, const Vec<4>& limits) {
  return tau.allFinite() && (tau.cwiseAbs().array() <= limits.array() + 1e-12).all();
}
}  // namespace

TEST_CASE("K and zeta at the RHI home configuration are the paper's 123 and 3.3") {
  const rhi::Rhi4Controller c(rhi4(), rhi4().effortLimits(), rhi4().homeJoints());
  // The paper prints 123 and 3.3: equal within that rounding (half a unit in the last digit).
  CHECK(c.majorAxis() == Approx(123.0).margin(0.5));
  CHECK(c.minorAxis() == Approx(3.3).margin(0.05));
  // u = [0, 1]: M_free = diag(K, zeta), M_stiff = diag(zeta, K) as in Section IV.
  CHECK(c.freeEllipsoid()(0, 0) == Approx(c.majorAxis()));
  CHECK(c.freeEllipsoid()(1, 1) == Approx(c.minorAxis()));
}

TEST_CASE("analytic gradient of nu matches central differences at random configurations") {
  const auto& m = rhi4();
  const Vec<4> w2 = fme::inverseSquaredLimits(m.effortLimits());
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int checked = 0;
  for (int trial = 0; trial < 100; ++trial) {
    const Vec<4> q = randomConfiguration(rng);
    Mat2 Mdes;
    fme::axisAlignedEllipsoid(Vec2(std::cos(7.0 * unit(rng)), std::sin(7.0 * unit(rng))), 1.0 + 100.0 * unit(rng),
                              1.0 + 10.0 * unit(rng), Mdes);
    Mat<2, 4> J;
    m.jacobian(q, J);
    Mat2 Mhat;
    // Skip near-singular draws: there nu blows up and both gradients lose meaning.
    if (!fme::weightedFme(J, w2, Mhat, 1e-3)) continue;
    double nu_a = 0.0, nu_f = 0.0;
    Vec<4> g_a, g_f;
    REQUIRE(fme::fmeCostGradient(m, q, J, w2, Mdes, fme::GradientMethod::kAnalytic, nu_a, g_a));
    REQUIRE(fme::fmeCostGradient(m, q, J, w2, Mdes, fme::GradientMethod::kFiniteDifference, nu_f, g_f));
    CHECK(nu_a == nu_f);
    // Central differences (h ~ 6e-6) are accurate to ~1e-9 relative here; 1e-6 leaves margin for
    // configurations with lambda_min / lambda_max down to 1e-3.
    CHECK((g_a - g_f).norm() <= 1e-6 * std::max(1.0, g_f.norm()));
    ++checked;
  }
  CHECK(checked > 80);
}

TEST_CASE("the null-space torque produces no end-effector force or acceleration") {
  const auto& m = rhi4();
  rhi::Rhi4Controller c(m, m.effortLimits(), m.homeJoints());
  std::mt19937 rng(2);
  std::normal_distribution<double> n01;
  for (int trial = 0; trial < 30; ++trial) {
    const Vec<4> q = randomConfiguration(rng);
    const Vec<4> qd(n01(rng), n01(rng), n01(rng), n01(rng));
    Vec<4> tau;
    if (c.tick(0.001 * trial, q, qd, Vec2::Zero(), tau) != Fault::kNone) continue;
    const Vec<4> tn = c.status().tau_null;
    Mat<2, 4> J;
    m.jacobian(q, J);
    Mat<4, 4> M;
    m.massMatrix(q, M);
    const Mat<4, 2> MinvJt = M.llt().solve(J.transpose());
    const Mat2 lambda = (J * MinvJt).inverse();
    const Vec2 force = lambda * J * M.llt().solve(tn);  // static force J#^T tau_N = Lambda J M^-1 tau_N
    CHECK(force.norm() <= 1e-9 * std::max(1.0, tn.norm()));
  }
}

TEST_CASE("the controller keeps every command within the torque limits and scales force along its direction") {
  const auto& m = rhi4();
  rhi::Rhi4Controller c(m, m.effortLimits(), m.homeJoints());
  std::mt19937 rng(8);
  std::normal_distribution<double> n01;
  for (int trial = 0; trial < 200; ++trial) {
    const Vec<4> q = randomConfiguration(rng);
    const Vec<4> qd = 3.0 * Vec<4>(n01(rng), n01(rng), n01(rng), n01(rng));
    const Vec2 F = 40.0 * Vec2(n01(rng), n01(rng));  // mostly beyond what the device can do
    Vec<4> tau;
    const Fault f = c.tick(0.001 * trial, q, qd, F, tau);
    REQUIRE(withinLimits(tau, m.effortLimits()));
    if (f != Fault::kNone) continue;
    const auto& st = c.status();
    CHECK(st.observer >= 0.0);
    CHECK(st.observer <= 1.0);
    // alpha F: same direction, shrunk until no primary torque exceeds its limit, one joint at it.
    CHECK(st.alpha <= 1.0);
    CHECK(std::abs(st.force(0) * F(1) - st.force(1) * F(0)) <= 1e-9 * F.squaredNorm());
    CHECK(st.force.dot(F) >= 0.0);
    CHECK(withinLimits(st.tau_primary, m.effortLimits()));
    if (st.alpha < 1.0) CHECK((st.tau_primary.cwiseAbs() - m.effortLimits()).maxCoeff() == Approx(0.0).margin(1e-12));
  }
}

TEST_CASE("bad input gives a fault and a safe command") {
  const auto& m = rhi4();
  rhi::Rhi4Controller c(m, m.effortLimits(), m.homeJoints());
  Vec<4> tau;
  const Vec<4> q(0.3, 0.2, -0.4, 0.5);
  SECTION("non-finite state or force: zero torque") {
    Vec<4> bad = q;
    bad(2) = std::nan("");
    CHECK(c.tick(0.0, bad, Vec<4>::Zero(), Vec2(1, 0), tau) == Fault::kNonFiniteInput);
    CHECK(tau.isZero());
    CHECK(c.tick(0.0, q, Vec<4>::Constant(std::numeric_limits<double>::infinity()), Vec2(1, 0), tau) == Fault::kNonFiniteInput);
    CHECK(tau.isZero());
    CHECK(c.tick(0.0, q, Vec<4>::Zero(), Vec2(std::nan(""), 0), tau) == Fault::kNonFiniteInput);
    CHECK(tau.isZero());
  }
  SECTION("singular Jacobian (all links aligned): primary task only") {
    const Vec<4> aligned(0.0, M_PI / 2, -M_PI / 2, 0.0);  // every link angle 0: J has rank 1
    const Vec2 F(0.0, 2.0);
    CHECK(c.tick(0.0, aligned, Vec<4>::Zero(), F, tau) == Fault::kSingular);
    Mat<2, 4> J;
    m.jacobian(aligned, J);
    Vec<4> primary = J.transpose() * F;
    scaleIntoBox(primary, m.effortLimits());
    CHECK((tau - primary).norm() < 1e-12);
    CHECK(c.status().tau_null.isZero());
  }
  SECTION("a desired ellipsoid that is not positive definite is refused") {
    Mat2 indefinite;
    indefinite << 1.0, 0.0, 0.0, -1.0;
    CHECK(c.setFreeEllipsoid(indefinite) == Fault::kInvalidParameter);
    Mat2 asymmetric;
    asymmetric << 1.0, 0.5, 0.0, 1.0;
    CHECK(c.setFreeEllipsoid(asymmetric) == Fault::kInvalidParameter);
    CHECK(c.setFreeEllipsoid(Mat2::Constant(std::nan(""))) == Fault::kInvalidParameter);
    CHECK(c.freeEllipsoid().isApprox(Mat2(Vec2(c.majorAxis(), c.minorAxis()).asDiagonal())));
    CHECK(c.tick(0.0, q, Vec<4>::Zero(), Vec2::Zero(), tau) == Fault::kNone);
  }
  SECTION("invalid options are refused at run time and at construction") {
    auto o = c.options();
    o.transition.enter_stiff_below = 0.99;  // eps1 > eps2
    CHECK(c.setOptions(o) == Fault::kInvalidParameter);
    o = c.options();
    o.beta = std::nan("");
    CHECK(c.setOptions(o) == Fault::kInvalidParameter);
    o = c.options();
    o.motion_direction.setZero();
    CHECK(c.setOptions(o) == Fault::kInvalidParameter);
    CHECK(c.options().beta == 20.0);
    CHECK_THROWS_AS(rhi::Rhi4Controller(m, Vec<4>(3, 3, 0, 1), m.homeJoints()), Error);
    CHECK_THROWS_AS(rhi::Rhi4Controller(m, m.effortLimits(), Vec<4>(0.0, M_PI / 2, -M_PI / 2, 0.0)), Error);
    o.motion_direction = Vec2(0, 1);
    o.mu = -1.0;
    CHECK_THROWS_AS(rhi::Rhi4Controller(m, m.effortLimits(), m.homeJoints(), o), Error);
  }
}

TEST_CASE("the controller tick allocates nothing, with and without contact") {
  const auto& m = rhi4();
  rhi::Rhi4Controller c(m, m.effortLimits(), m.homeJoints());
  Vec<4> tau;
  const Vec<4> q(0.3, 0.2, -0.4, 0.5), qd(0.1, -0.2, 0.3, 0.0);
  tools::AllocationScope scope;
  for (int k = 0; k < 100; ++k) {
    c.tick(0.001 * k, q, qd, Vec2::Zero(), tau);
    c.tick(0.001 * k, q, qd, Vec2(0.0, -30.0), tau);  // saturating: observer, transition, scaling
  }
  auto o = c.options();
  o.gradient = fme::GradientMethod::kFiniteDifference;
  c.setOptions(o);
  c.tick(1.0, q, qd, Vec2(0.0, -3.0), tau);
  CHECK(scope.count() == 0);
}

TEST_CASE("free-motion ticks skip the contact-only work") {
  const auto& m = rhi4();
  rhi::Rhi4Controller c(m, m.effortLimits(), m.homeJoints());
  Vec<4> tau;
  const Vec<4> q(0.3, 0.2, -0.4, 0.5);
  c.tick(0.0, q, Vec<4>::Zero(), Vec2::Zero(), tau);
  CHECK(c.status().skipped_contact_work);
  c.tick(0.001, q, Vec<4>::Zero(), Vec2(0.0, -1.0), tau);
  CHECK_FALSE(c.status().skipped_contact_work);
}

TEST_CASE("stiff ellipsoid gives more force along u than the free one over the workspace") {
  // Coarse grid (10 cm) of the Fig. 10 study; the tool runs it at 2.5 cm.
  const auto map = rhi::workspaceRatioMap(rhi4(), 0.1, 0.7, Vec2(0.0, 1.0), 2);
  std::size_t valid = 0, above = 0, pinned = 0, weaker = 0, rematched = 0;
  for (const auto& p : map) {
    if (!std::isfinite(p.ratio)) {
      CHECK(p.kind == rhi::RatioKind::kUnreachable);
      continue;
    }
    ++valid;
    CAPTURE(p.x.transpose(), p.ratio, rhi::toString(p.kind), p.global_ratio, p.free_cost_excess,
            p.stiff_cost_excess);
    // The paper's "> 1 everywhere", except at points shown by computation to be of kind (a): the
    // dense scan's global minima are the matches and the stiff one is not stronger, or (b): both
    // matches inside the limit margin of the same bound. Nothing else (no missed minimum).
    if (p.rematched) {
      // The dense scan's start replaced a match only where it lowered the cost.
      ++rematched;
      CHECK(std::max(p.free_cost_excess, p.stiff_cost_excess) > 0.0);
      CHECK(p.global_ratio == p.ratio);
    }
    if (p.ratio > 1.0) {
      CHECK(p.kind == rhi::RatioKind::kAbove);
      ++above;
      continue;
    }
    CHECK(p.kind != rhi::RatioKind::kUnexplained);
    CHECK(p.global_ratio == p.ratio);  // the matches at ratio <= 1 are the global minima
    if (p.kind == rhi::RatioKind::kWeakerGlobalMinimum) {
      ++weaker;
      CHECK(p.global_ratio <= 1.0);
    }
    if (p.kind == rhi::RatioKind::kPinnedAtSameStop) {
      ++pinned;
      CHECK(p.free_bound == p.stiff_bound);
      CHECK(p.free_limit_distance < 0.25);
      CHECK(p.stiff_limit_distance < 0.25);
    }
    CHECK(p.ratio > 0.95);  // neither kind costs more than a few % on this grid
  }
  CHECK(valid > 100);
  WARN("Fig. 10 test grid: " << valid << " reachable, " << above << " with ratio > 1, " << weaker << " of kind (a), "
                             << pinned << " of kind (b), " << rematched << " rematched from the dense scan");
  // Every reachable point is accounted for. (The former check "> 1 at >= 95 %" is replaced by this:
  // the grid-started matching reaches points near the border within the limits that the 5 fixed
  // starts did not, most of kind (a) or (b), and the share is 112 of 117, one point lifted above 1
  // by the dense scan's start.)
  CHECK(above + weaker + pinned == valid);
}

TEST_CASE("the transition removes the jump in the null-space torque") {
  const auto smooth = rhi::runTransition(rhi4(), rhi4Product(), true);
  const auto abrupt = rhi::runTransition(rhi4(), rhi4Product(), false);
  // Both runs switch to the stiff ellipsoid and back.
  auto reached = [](const rhi::TransitionRun& r, double omega) {
    for (const auto& s : r.samples)
      if (s.omega == omega) return true;
    return false;
  };
  CHECK(reached(smooth, 0.0));
  CHECK(reached(abrupt, 0.0));
  CHECK(smooth.transition_duration == Approx(0.5).margin(0.01));
  // Without smoothing the switch steps the gradient term by beta |d nu/dq (M_stiff) - d nu/dq (M_free)|,
  // several N m in one tick; with it the per-tick change stays below 1.5 N m (the largest step left
  // is at the onset of contact, not at the switch).
  CHECK(abrupt.max_null_torque_jump > 3.0);
  CHECK(smooth.max_null_torque_jump < 1.5);
}

TEST_CASE("3-DoF example: stiff ellipsoid renders F_e without saturation, free one saturates") {
  const auto ex = rhi::runExample3(test::planar3Model(), 4.0, 1e-2);
  CHECK(ex.configs[2].min_alpha == 1.0);
  CHECK(ex.configs[2].peak_force == Approx(3.5).epsilon(1e-3));
  CHECK(ex.configs[1].peak_force < ex.configs[0].peak_force);
  CHECK(ex.configs[0].peak_force < 3.5);
  // The optimized configurations keep the end effector where it was held.
  const auto& m = test::planar3Model();
  for (const auto& cfg : ex.configs) {
    Vec2 x;
    m.forward(cfg.q, x);
    CHECK((x - ex.x_end).norm() < 1e-9);
  }
}

TEST_CASE("palpation: stiff ellipsoid is stronger and heavier along u, both within the joint limits") {
  const auto free_case = rhi::runPalpation(rhi4(), rhi4Product(), FmeEllipsoidMode::kFree, {}, 3);
  const auto stiff_case = rhi::runPalpation(rhi4(), rhi4Product(), FmeEllipsoidMode::kStiff, {}, 3);
  CHECK(stiff_case.peak_force > 1.2 * free_case.peak_force);
  // The rendered force saturates at the static capability of the settled configuration (alpha
  // scaling keeps it there; 2 % covers the configuration drift during the push).
  CHECK(free_case.peak_force == Approx(free_case.capability).epsilon(0.02));
  CHECK(stiff_case.peak_force == Approx(stiff_case.capability).epsilon(0.02));
  // The self-motion never takes the arm through a (assumed) mechanical stop.
  CHECK(free_case.limit_distance > 0.0);
  CHECK(stiff_case.limit_distance > 0.0);
  REQUIRE(free_case.fit_valid);
  REQUIRE(stiff_case.fit_valid);
  CHECK(stiff_case.inertia_identified > free_case.inertia_identified);
  CHECK(stiff_case.friction_model > free_case.friction_model);
  // Least squares recovers the model's apparent inertia (averaged over the samples' configurations)
  // within 15 %.
  CHECK(stiff_case.inertia_identified == Approx(stiff_case.inertia_model).epsilon(0.15));
  CHECK(free_case.inertia_identified == Approx(free_case.inertia_model).epsilon(0.15));
  // Friction (FME gradient paused during the identification, see runPalpation): positive and ordered
  // as in the paper, and both terms recover the model's back-drive friction along u, (J# u)^T f(q_dot)
  // at the samples' joint velocities, within 25 % (free viscous: the guide's compliance across u
  // couples the cross-axis inertia into v, +0.01 N s/m on 0.06). The no-self-motion reflection
  // u^T J#^T B J# u is not the reference: the paused self-motion moves the joints otherwise (README).
  INFO("free viscous " << free_case.friction_identified << " vs " << free_case.friction_reference << ", stiff "
                       << stiff_case.friction_identified << " vs " << stiff_case.friction_reference);
  CHECK(free_case.friction_identified > 0.0);
  CHECK(stiff_case.friction_identified > free_case.friction_identified);
  CHECK(free_case.friction_identified == Approx(free_case.friction_reference).epsilon(0.25));
  CHECK(stiff_case.friction_identified == Approx(stiff_case.friction_reference).epsilon(0.25));
  CHECK(free_case.coulomb_identified == Approx(free_case.coulomb_reference).epsilon(0.25));
  CHECK(stiff_case.coulomb_identified == Approx(stiff_case.coulomb_reference).epsilon(0.25));
}
