// The FME controller's null-space envelope (ramp after reset and after a fault, norm bound, energy tank), the
// contact-direction filter and freeze of the stiff ellipsoid, and the joint-limit brake's inertia.
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <random>

#include "rhi_fixtures.hpp"
#include "uhaptics/backends/simulated_planar_linkage.hpp"
#include "uhaptics/core/decompositions.hpp"
#include "uhaptics/experiments/rhi_experiments.hpp"

using namespace uhaptics;

namespace {
using rhi_test::rhi4;

// tau_N = s c with s >= 0: the envelope kept the command's direction.
bool sameDirection(const Vec<4>& tau_null, const Vec<4>& command) {
  const double s = tau_null.dot(command) / command.squaredNorm();
  return s >= 0.0 && (tau_null - s * command).norm() <= 1e-12 * (1.0 + command.norm());
}

// The major axis (unit, sign-free) of a desired ellipsoid.
Vec2 majorAxis(const Mat2& ellipsoid) {
  Vec2 lambda;
  Mat2 vectors;
  REQUIRE(symmetricEigen(ellipsoid, lambda, &vectors));
  return vectors.col(1);
}
}  // namespace

TEST_CASE("null-space envelope: rises from zero after reset and after a fault, bounded, direction and primary kept") {
  const auto& m = rhi4();
  rhi::Rhi4Controller::Options o;
  const double bound = 0.5, ramp = 0.25, dt = 1e-3;
  o.max_null_space_torque = bound;
  o.null_space_ramp_time = ramp;
  rhi::Rhi4Controller enveloped(m, m.effortLimits(), m.homeJoints(), o), paper(m, m.effortLimits(), m.homeJoints());
  // A fixed state at home, so the command (5.4 N m, above the bound) is the same every tick and
  // every change of tau_N is the envelope's.
  const Vec<4> q = m.homeJoints(), qd = Vec<4>::Zero();
  Vec<4> tau, tau_paper;
  auto run = [&](int first, int ticks) {
    Vec<4> previous = enveloped.status().tau_null;
    double largest_step = 0.0;
    for (int k = first; k < first + ticks; ++k) {
      const double t = k * dt;
      const Vec2 F = k % 100 >= 50 ? Vec2(0.3, -2.0) : Vec2::Zero();  // contact half the time
      REQUIRE(enveloped.tick(t, q, qd, F, tau) == Fault::kNone);
      REQUIRE(paper.tick(t, q, qd, F, tau_paper) == Fault::kNone);
      const auto& s = enveloped.status();
      REQUIRE(s.tau_null_command.norm() > bound);  // the bound is what limits here
      // The primary task is untouched by the envelope (bit for bit: same arithmetic).
      CHECK(s.tau_primary == paper.status().tau_primary);
      CHECK(s.alpha == paper.status().alpha);
      CHECK(sameDirection(s.tau_null, s.tau_null_command));
      // |tau_N| = r B with r the documented half-cosine of (t - t_0) / ramp (1e-12: round-off of the scale).
      const double u = (k - first) * dt / ramp;
      const double r = u < 1.0 ? 0.5 * (1.0 - std::cos(M_PI * u)) : 1.0;
      CHECK(s.tau_null.norm() == Approx(r * bound).margin(1e-12));
      largest_step = std::max(largest_step, (s.tau_null - previous).norm());
      previous = s.tau_null;
    }
    return largest_step;
  };
  // From reset (construction): zero at the first tick, B after the ramp, never a step above the
  // half cosine's steepest slope pi dt / (2 T) B (0.0031 N m at 1 kHz, 0.25 s).
  const double steepest = M_PI * dt / (2.0 * ramp) * bound;
  CHECK(run(0, 400) <= steepest * (1.0 + 1e-9));
  // The control: the paper's controller (no envelope) commands 3 N m at once from the same state.
  CHECK(paper.status().tau_null.norm() > 2.0);
  // A fault drops the null space; it comes back through the ramp, not as a step.
  CHECK(enveloped.tick(0.4, Vec<4>::Constant(std::nan("")), qd, Vec2::Zero(), tau) == Fault::kNonFiniteInput);
  CHECK(enveloped.status().tau_null.isZero());
  CHECK(run(401, 300) <= steepest * (1.0 + 1e-9));
  // So does reset().
  enveloped.reset();
  CHECK(run(701, 300) <= steepest * (1.0 + 1e-9));
}

TEST_CASE("envelope options: invalid values are refused, the defaults are the paper's controller") {
  const auto& m = rhi4();
  rhi::Rhi4Controller c(m, m.effortLimits(), m.homeJoints());
  CHECK(std::isinf(c.options().max_null_space_torque));
  CHECK(c.options().null_space_ramp_time == 0.0);
  CHECK(c.options().stiff_direction_time == 0.0);
  CHECK(std::isinf(c.options().null_space_tank_capacity));  // no tank
  CHECK(std::isinf(c.status().null_space_tank));
  for (const double bad : {0.0, -1.0, std::nan("")}) {
    auto o = c.options();
    o.max_null_space_torque = bad;
    CHECK(c.setOptions(o) == Fault::kInvalidParameter);
    o = c.options();
    o.null_space_tank_capacity = bad;
    CHECK(c.setOptions(o) == Fault::kInvalidParameter);
  }
  for (const double bad : {-1e-3, std::nan(""), std::numeric_limits<double>::infinity()}) {
    auto o = c.options();
    o.null_space_ramp_time = bad;
    CHECK(c.setOptions(o) == Fault::kInvalidParameter);
    o = c.options();
    o.stiff_direction_time = bad;
    CHECK(c.setOptions(o) == Fault::kInvalidParameter);
    o = c.options();
    o.null_space_tank_refill = bad;
    CHECK(c.setOptions(o) == Fault::kInvalidParameter);
  }
  CHECK(std::isinf(c.options().max_null_space_torque));  // refused: the previous options stay
}

TEST_CASE("the stiff ellipsoid follows the contact force through its filter and stays put while it is left") {
  const auto& m = rhi4();
  const double dt = 1e-3, filter = 0.02;
  rhi::Rhi4Controller::Options o;
  o.stiff_direction_time = filter;
  rhi::Rhi4Controller c(m, m.effortLimits(), m.homeJoints(), o);
  const Vec<4> q = m.homeJoints(), qd = Vec<4>::Zero();
  Vec<4> tau;
  int k = 0;
  auto tick = [&](const Vec2& F) {
    REQUIRE(c.tick(k * dt, q, qd, F, tau) == Fault::kNone);
    ++k;
  };
  // A force that saturates the primary task: the observer switches to the stiff ellipsoid at once,
  // whose axis is this force's direction (taken directly while the free ellipsoid is settled).
  const Vec2 push(0.0, -30.0);
  tick(push);
  REQUIRE(c.status().omega_target == 0.0);
  CHECK(std::abs(majorAxis(c.stiffEllipsoid()).dot(push.normalized())) == Approx(1.0).margin(1e-12));
  // Turned by 10 deg in one tick: the axis moves by the filter's share 1 - exp(-dt / T) of it.
  const double turn = 10.0 * M_PI / 180.0;
  const Vec2 turned = Eigen::Rotation2Dd(turn) * push;
  tick(turned);
  const double share = 1.0 - std::exp(-dt / filter);
  const Vec2 expected = (push.normalized() + share * (turned.normalized() - push.normalized())).normalized();
  CHECK(std::abs(majorAxis(c.stiffEllipsoid()).dot(expected)) == Approx(1.0).margin(1e-12));
  const double moved = std::acos(std::min(1.0, std::abs(majorAxis(c.stiffEllipsoid()).dot(push.normalized()))));
  CHECK(moved == Approx(std::atan2(share * std::sin(turn), 1.0 - share + share * std::cos(turn))).epsilon(1e-6));
  CHECK(moved < 0.06 * turn);  // 4.9 % of the turn in one tick
  while (c.status().omega > 0.0) tick(turned);  // the blend to stiff completes (rho |M_free - M_stiff|: 0.5 s)
  // The force falls (V >= eps2): the blend back to free starts, and the force's direction turns
  // through 180 deg within a few ticks as it vanishes (a proxy leaving a surface).
  tick(0.2 * turned.normalized());
  REQUIRE(c.status().omega_target == 1.0);
  const Mat2 held = c.stiffEllipsoid();
  for (int i = 0; i < 20 && c.status().omega < 1.0; ++i) {
    tick(0.1 * (Eigen::Rotation2Dd(M_PI * i / 19.0) * turned.normalized()));
    CHECK((c.stiffEllipsoid() - held).norm() == 0.0);
  }
  // The control: without the filter the axis takes each tick's force (the paper).
  rhi::Rhi4Controller paper(m, m.effortLimits(), m.homeJoints());
  REQUIRE(paper.tick(0.0, q, qd, push, tau) == Fault::kNone);
  REQUIRE(paper.tick(dt, q, qd, turned, tau) == Fault::kNone);
  CHECK(std::abs(majorAxis(paper.stiffEllipsoid()).dot(turned.normalized())) == Approx(1.0).margin(1e-12));
}

TEST_CASE("the joint-limit brake removes dt / limit_brake_time of the excess approach speed per tick") {
  // Velocity damper: a limited coordinate s_j = C_j q approaching its bound faster than the cap
  // (limit_speed, 2 rad/s, outside the margin) is braked by a null-space torque that decelerates
  // it at excess / limit_brake_time, at every configuration where the null space can move it.
  const auto& m = rhi4();
  const rhi::Rhi4Controller::Options o;
  rhi::Rhi4Controller c(m, m.effortLimits(), m.homeJoints(), o);
  const JointLimits<4>& limits = m.jointLimits();
  const Mat<4, 4> C = limits.map;
  const Mat<4, 4> Cinv = C.inverse();
  std::mt19937 rng(12);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int checked = 0, floored = 0;
  // The whole arm's inertia C_j M C_j^T over the one the null space shows, 1 / (C_j M^-1 P C_j^T):
  // a brake sized by the former has a per-tick gain of this ratio times dt / limit_brake_time,
  // stable below 2 (ratio 10).
  double worst_overestimate = 0.0;
  for (int trial = 0; trial < 300; ++trial) {
    // Limited coordinates inside the bounds, farther than the margin from each (no barrier torque).
    Vec<4> s;
    for (int j = 0; j < 4; ++j) {
      const double lo = limits.lower(j) + o.limit_margin, hi = limits.upper(j) - o.limit_margin;
      s(j) = lo + (hi - lo) * unit(rng);
    }
    const Vec<4> q = Cinv * s;
    const int j = trial % 4;
    const double speed = 3.0, excess = speed - o.limit_speed;  // towards the upper bound of s_j only
    const Vec<4> qd = Cinv * (speed * Vec<4>::Unit(j));
    Vec<4> tau;
    if (c.tick(trial * 1e-3, q, qd, Vec2::Zero(), tau) != Fault::kNone) continue;
    Mat<4, 4> M;
    m.massMatrix(q, M);
    Mat<2, 4> J;
    m.jacobian(q, J);
    const Mat<4, 4> Minv = M.inverse();
    const Mat<4, 2> Jsharp = Minv * J.transpose() * (J * Minv * J.transpose()).inverse();
    const Mat<4, 4> P = Mat<4, 4>::Identity() - J.transpose() * Jsharp.transpose();
    const auto row = C.row(j);
    const double null_mobility = row * Minv * P * row.transpose(), free_mobility = row * Minv * row.transpose();
    const double s_ddot = row * Minv * c.status().tau_limit_command;
    // 1e-9 relative: the controller and this check invert M and J M^-1 J^T separately (condition < 1e3).
    if (null_mobility >= 0.01 * free_mobility) {
      CHECK(s_ddot == Approx(-excess / o.limit_brake_time).epsilon(1e-9));
      ++checked;
    } else {
      CHECK(s_ddot < 0.0);  // capped inertia: braking, more gently
      CHECK(s_ddot > -excess / o.limit_brake_time);
      ++floored;
    }
    worst_overestimate = std::max(worst_overestimate, (row * M * row.transpose()).value() * null_mobility);
  }
  INFO("whole-arm inertia C M C^T overestimates up to " << worst_overestimate << "x; " << floored << " capped");
  CHECK(checked > 250);
  // The control: on this sample a brake sized by the whole arm's inertia is unstable in discrete
  // time somewhere, so the null-space inertia is what keeps it stable.
  CHECK(worst_overestimate > 10.0);
}

TEST_CASE("null-space energy tank: the self-motion gives the arm at most capacity + refill t, measured from the plant") {
  const auto& m = rhi4();
  const double dt = 1e-3, capacity = 0.01, refill = 0.002;  // 10 mJ, 2 mW
  // Free motion whose desired ellipsoid turns by 90 deg every 0.4 s: each turn sends the arm along
  // its self-motion manifold, work the null-space torque does on it that only friction takes out.
  auto run = [&](bool tank, double& worst_excess) {
    rhi::Rhi4Controller::Options o;
    o.max_null_space_torque = 0.5;
    if (tank) {
      o.null_space_tank_capacity = capacity;
      o.null_space_tank_refill = refill;
    }
    rhi::Rhi4Controller c(m, m.effortLimits(), m.homeJoints(), o);
    SimulatedPlanarLinkage<4> plant(m);
    plant.reset(m.homeJoints());
    double work = 0.0;  // [J] the applied null-space torque's work on the plant, tau_N^T dq per period
    worst_excess = -std::numeric_limits<double>::infinity();
    Vec<4> tau;
    for (int k = 0; k < 4000; ++k) {
      const double t = k * dt;
      if (k % 400 == 0) {
        o.motion_direction = (k / 400) % 2 == 0 ? Vec2::UnitX() : Vec2::UnitY();
        REQUIRE(c.setOptions(o) == Fault::kNone);
      }
      REQUIRE(c.tick(t, plant.position(), plant.velocity(), Vec2::Zero(), tau) == Fault::kNone);
      const Vec<4> tau_null = c.status().tau_null, before = plant.position();
      REQUIRE(plant.step(tau, dt) == Fault::kNone);
      work += tau_null.dot(plant.position() - before);
      worst_excess = std::max(worst_excess, work - (capacity + refill * (t + dt)));
      // The tank's scale is a fade, never an amplification; the torque keeps its direction.
      CHECK(c.status().null_space_tank_scale >= 0.0);
      CHECK(c.status().null_space_tank_scale <= 1.0);
    }
    return work;
  };
  double excess_tank = 0.0, excess_free = 0.0;
  const double with_tank = run(true, excess_tank), without = run(false, excess_free);
  INFO("null-space work: " << 1e3 * with_tank << " mJ with the tank, " << 1e3 * without << " mJ without");
  // The bound holds at every instant, up to one period's work booked after the fact (0.1 mJ).
  CHECK(excess_tank <= 1e-4);
  // The control: without the tank the same turns give the arm more than the tank allows.
  CHECK(excess_free > 5e-3);
}
