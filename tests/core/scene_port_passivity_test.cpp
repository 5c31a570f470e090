// ScenePortPassivity against closed forms: the generated energy of a sampled spring is K dq^2 / 2
// per period (the trapezoidal reference), the booking follows the command delay, the cap is the
// inertia an effort along the scene's direction meets, a release forgets the excess, displacements
// inside the dead band get no damping, a brake that keeps pushing with the motion is throttled, and
// bad options are refused.
#include <catch2/catch.hpp>

#include <cmath>
#include <vector>

#include "uhaptics/core/scene_port_passivity.hpp"

using namespace uhaptics;

namespace {

constexpr double kT = 1e-3;
using Vector = ScenePortPassivity::Vector;

Vector vec(std::initializer_list<double> values) {
  Vector v(static_cast<Eigen::Index>(values.size()));
  Eigen::Index i = 0;
  for (const double x : values) v(i++) = x;
  return v;
}

// A path into a 1-joint spring wall s = -K q (q > 0 inside) from its surface and about inside it:
// q_k for k = 0..n-1.
std::vector<double> path(int n) {
  std::vector<double> q(static_cast<std::size_t>(n));
  for (int k = 0; k < n; ++k) q[static_cast<std::size_t>(k)] = 1e-3 * (1.0 - std::cos(0.05 * k));
  return q;
}

}  // namespace

TEST_CASE("scene port passivity: a sampled spring generates K dq^2 / 2 per period, booked at the command delay") {
  constexpr double K = 300.0;
  const std::vector<double> q = path(400);
  for (const int delay : {0, 1, 3}) {
    INFO("delay " << delay);
    ScenePortPassivity::Options o;
    o.enabled = false;  // observe only: the command is the spring's
    o.command_delay = delay;
    ScenePortPassivity layer(o, 1);
    Vector u;
    double booked = 0.0, generated = 0.0;
    std::vector<double> sent;
    for (std::size_t k = 0; k < q.size(); ++k) {
      const Vector s = vec({-K * q[k]});
      REQUIRE(layer.update(vec({q[k]}), s, s, kT, u) == Fault::kNone);
      CHECK(u(0) == s(0));  // bit for bit
      if (k > 0 && k > static_cast<std::size_t>(delay)) {
        // Period k-1 -> k: the command sent at k-1-delay acted; the continuous spring's work is the
        // trapezoid of -K q.
        const double dq = q[k] - q[k - 1];
        const double applied = sent[k - 1 - static_cast<std::size_t>(delay)];
        booked += applied * dq;
        generated += (applied - 0.5 * (-K * q[k - 1] - K * q[k])) * dq;
      }
      sent.push_back(s(0));
    }
    CHECK(layer.bookedWork() == Approx(booked).epsilon(1e-12));
    CHECK(layer.generated() == Approx(generated).epsilon(1e-12));
    if (delay == 0) {
      double closed_form = 0.0;  // sum of K dq^2 / 2
      for (std::size_t k = 1; k < q.size(); ++k) closed_form += 0.5 * K * (q[k] - q[k - 1]) * (q[k] - q[k - 1]);
      CHECK(layer.generated() == Approx(closed_form).epsilon(1e-9));
    }
    CHECK(layer.generated() > 0.0);  // a sampled spring is never lossless
    CHECK(layer.activeTicks() == 0);
  }
}

TEST_CASE("scene port passivity: a scene that gives back more than it took in is charged for it") {
  // A negative damper s = +B v rendered along a path: its continuous-time work B v^2 T per period
  // overdraws a store that starts empty, so the whole of it is generated.
  constexpr double B = 2.0;
  ScenePortPassivity::Options o;
  o.enabled = false;
  ScenePortPassivity layer(o, 1);
  Vector u;
  double q = 0.0, previous = 0.0, closed_form = 0.0, s_previous = 0.0;
  for (int k = 0; k < 200; ++k) {
    q = 1e-2 * std::sin(0.03 * k);
    const double s = k == 0 ? 0.0 : B * (q - previous) / kT;
    if (k > 0) closed_form += s_previous * (q - previous);  // the applied (held) effort's work
    REQUIRE(layer.update(vec({q}), vec({s}), vec({s}), kT, u) == Fault::kNone);
    previous = q;
    s_previous = s;
  }
  CHECK(layer.bookedWork() == Approx(closed_form).epsilon(1e-12));
  // All of it: generated = booked + what the store holds at the end (>= 0, the trapezoid's credit
  // where the rate turns).
  CHECK(layer.generated() >= layer.bookedWork());
  CHECK(layer.generated() == Approx(layer.bookedWork()).epsilon(0.05));
  CHECK(layer.generated() > 0.0);
}

TEST_CASE("scene port passivity: the cap is the inertia along the scene's effort over 2 T (1 + d)") {
  ScenePortPassivity::Options o;
  o.inertia.resize(2, 2);
  o.inertia << 2.0, 0.5, 0.5, 1.0;
  o.command_delay = 1;
  const ScenePortPassivity layer(o, 2);
  const Vector e = vec({0.6, 0.8});
  const double mobility = e.dot(o.inertia.inverse() * e);
  CHECK(layer.capAlong(e, kT) == Approx(1.0 / (mobility * 2.0 * kT * 2.0)).epsilon(1e-12));
  o.max_damping = 10.0;  // an explicit cap below it wins
  CHECK(ScenePortPassivity(o, 2).capAlong(e, kT) == 10.0);
  o.inertia.resize(0, 0);  // no inertia: the explicit cap alone, or none
  CHECK(ScenePortPassivity(o, 2).capAlong(e, kT) == 10.0);
  o.max_damping = std::nan("");
  CHECK(ScenePortPassivity(o, 2).capAlong(e, kT) == 0.0);
}

TEST_CASE("scene port passivity: it brakes a ring along the scene's effort, forgets at a release, not inside the dead band") {
  constexpr double K = 300.0;
  ScenePortPassivity::Options o;
  o.inertia = ScenePortPassivity::Matrix::Identity(2, 2) * 1e-3;
  o.resolution = vec({1e-5, 1e-5});
  ScenePortPassivity layer(o, 2);
  Vector u;
  // Joint 0 rings inside the wall; joint 1 moves freely and carries no scene effort.
  for (int k = 0; k < 40; ++k) {
    const double q0 = 1e-3 + 2e-4 * std::sin(0.7 * k);
    const Vector s = vec({-K * q0, 0.0});
    const Vector own = vec({0.0, 0.3});  // a field of the policy's own on joint 1
    REQUIRE(layer.update(vec({q0, 0.01 * k}), s + own, s, kT, u) == Fault::kNone);
    CHECK(u(1) == own(1));  // never braked: not the scene's direction
  }
  CHECK(layer.activeTicks() > 0);
  CHECK(layer.dissipated() > 0.0);
  CHECK(layer.lastDamping() <= layer.capAlong(vec({1.0, 0.0}), kT));
  // A release: no scene effort, nothing on the balance, no damping.
  REQUIRE(layer.update(vec({0.0, 0.5}), vec({0.0, 0.3}), vec({0.0, 0.0}), kT, u) == Fault::kNone);
  CHECK(layer.excess() == 0.0);
  CHECK(u(0) == 0.0);
  // Back into a stiff wall (the step in generates energy), then displacements inside half a sensor
  // step: they carry no rate, so no damping however much is generated.
  REQUIRE(layer.update(vec({1e-3, 0.5}), vec({-100.0, 0.0}), vec({-100.0, 0.0}), kT, u) == Fault::kNone);
  const auto active = layer.activeTicks();
  for (int k = 0; k < 20; ++k) {
    const double q0 = 1e-3 + (k % 2 == 0 ? 2e-6 : -2e-6);
    const Vector s = vec({-1e5 * q0, 0.0});
    REQUIRE(layer.update(vec({q0, 0.5}), s, s, kT, u) == Fault::kNone);
    CHECK(u(0) == s(0));
  }
  CHECK(layer.activeTicks() == active);
  CHECK(layer.excess() > 0.0);
}

TEST_CASE("scene port passivity: brakes that push with the motion (a flickering count) are throttled") {
  // A quantized joint flickering by one count in a stiff wall: every flip generates K c^2 / 2, and a
  // damper on the last displacement always acts against the flip just gone, i.e. with the next one.
  constexpr double K = 1e4, c = 1e-3, m = 1e-3;
  ScenePortPassivity::Options o;
  o.inertia = ScenePortPassivity::Matrix::Identity(1, 1) * m;
  o.resolution = vec({c});
  ScenePortPassivity layer(o, 1);
  const double cap = m / (2.0 * kT);
  Vector u;
  double worst = 0.0;  // the least work one period's brake took from the user (negative: it gave)
  double previous_dissipated = 0.0;
  for (int k = 0; k < 200; ++k) {
    const double q = k % 2 == 0 ? 2.0 * c : 3.0 * c;
    const Vector s = vec({-K * q});
    REQUIRE(layer.update(vec({q}), s, s, kT, u) == Fault::kNone);
    worst = std::min(worst, layer.dissipated() - previous_dissipated);
    previous_dissipated = layer.dissipated();
  }
  const double one_full_brake = cap * (c / kT) * c;  // the capped brake's work over one flip
  INFO("dissipated " << layer.dissipated() << " J, one capped brake " << one_full_brake << " J");
  CHECK(worst < 0.0);  // the brakes did push with the flips...
  CHECK(layer.dissipated() > -12.0 * one_full_brake);  // ...about ten capped brakes' worth in all
  CHECK(layer.lastDamping() < 1e-3 * cap);  // and the cap has shrunk to nothing
}

TEST_CASE("scene port passivity: bad options and input are refused with a zero command") {
  ScenePortPassivity::Options o;
  CHECK_THROWS_AS(ScenePortPassivity(o, 0), Error);
  CHECK_THROWS_AS(ScenePortPassivity(o, kScenePortMaxDim + 1), Error);
  o.command_delay = 4;
  CHECK_THROWS_AS(ScenePortPassivity(o, 1), Error);
  o.command_delay = 0;
  o.inertia = ScenePortPassivity::Matrix::Identity(2, 2) * -1.0;  // not positive definite
  CHECK_THROWS_AS(ScenePortPassivity(o, 2), Error);
  o.inertia(0, 1) = 0.5;  // not symmetric
  CHECK_THROWS_AS(ScenePortPassivity(o, 2), Error);
  o.inertia = ScenePortPassivity::Matrix::Identity(3, 3);  // not dim x dim
  CHECK_THROWS_AS(ScenePortPassivity(o, 2), Error);
  o.inertia.resize(0, 0);
  o.resolution = vec({1e-3});  // one entry for two joints
  CHECK_THROWS_AS(ScenePortPassivity(o, 2), Error);
  o.resolution.resize(0);
  o.max_damping = -1.0;
  CHECK_THROWS_AS(ScenePortPassivity(o, 2), Error);
  o.max_damping = 1.0;
  ScenePortPassivity layer(o, 2);
  Vector u;
  CHECK(layer.update(vec({0.0, std::nan("")}), vec({1.0, 1.0}), vec({1.0, 1.0}), kT, u) == Fault::kNonFiniteInput);
  CHECK(u.isZero(0.0));
  CHECK(layer.update(vec({0.0, 0.0}), vec({1.0, 1.0}), vec({1.0, 1.0}), 0.0, u) == Fault::kInvalidParameter);
  CHECK(layer.update(vec({0.0}), vec({1.0, 1.0}), vec({1.0, 1.0}), kT, u) == Fault::kInvalidParameter);
  CHECK(layer.faults() == 3);
}
