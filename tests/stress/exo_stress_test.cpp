// Stress suite, finger exoskeleton: the four underactuated renderers under random, out-of-range,
// non-finite and singular inputs and extreme gains, and an energy check over closed finger motions.
#include <catch2/catch.hpp>
#include <cmath>

#include "renderer_fixtures.hpp"
#include "stress_support.hpp"
#include "uhaptics/core/passivity_observer.hpp"
#include "uhaptics/models/exo_finger_model.hpp"
#include "uhaptics/renderers/underactuated_renderers.hpp"

using namespace uhaptics;
using Model = ExoFingerModel;

namespace {

UnderactuatedGains<Model> gainsWith(double zx, double zq) { return test::exoGains(zx, zq); }

// Every tick either faults with an exactly-zero command, or returns a finite command within limits.
template <class Renderer>
void hammer(Renderer& r, stress::AdversarialSource& src, int n, stress::Tally& t) {
  const auto& lo = test::exoModel().jointLimits().lower;
  const auto& hi = test::exoModel().jointLimits().upper;
  const auto& xlo = test::exoModel().taskLower();
  const auto& xhi = test::exoModel().taskUpper();
  Vec<1> tau;
  for (int i = 0; i < n; ++i) {
    const Vec2 q(src.around(lo(0), hi(0)), src.around(lo(1), hi(1)));
    const Vec2 xp(src.around(xlo(0), xhi(0)), src.around(xlo(1), xhi(1)));
    const Fault f = r.tick(q, xp, tau);
    ++t.cases;
    if (f != Fault::kNone) {
      ++t.faults;
      if (!tau.isZero(0.0)) ++t.violations;
    } else {
      if (r.last().clamped) ++t.clamped;
      if (!tau.allFinite() || std::abs(tau(0)) > test::exoModel().effortLimits()(0)) ++t.violations;
    }
  }
}
}  // namespace

TEST_CASE("exo renderers: random, out-of-range and non-finite states and proxies, gains 1e-9..1e9") {
  stress::AdversarialSource src(20261122);
  const int per_gain = 400 * stress::scale();
  stress::Tally standard{"exo standard"}, nullspace{"exo null-space"}, linear{"exo subspace (linearized)"},
      nonlinear{"exo subspace (nonlinear)"};
  for (int g = 0; g < 12; ++g) {
    const auto gains = gainsWith(src.logUniform(-9, 9), src.logUniform(-9, 9));
    StandardRenderer<Model> a(test::exoModel(), gains);
    NullSpaceRenderer<Model> b(test::exoModel(), gains);
    LinearizedSubspaceRenderer<Model> c(test::exoModel(), gains);
    NonlinearSubspaceRenderer<Model> d(test::exoModel(), gains);
    hammer(a, src, per_gain, standard);
    hammer(b, src, per_gain, nullspace);
    hammer(c, src, per_gain, linear);
    hammer(d, src, per_gain, nonlinear);
  }
  for (const auto* t : {&standard, &nullspace, &linear, &nonlinear}) {
    t->print();
    CHECK(t->violations == 0);
    CHECK(t->cases == 12L * per_gain);
  }
}

TEST_CASE("exo renderers reject invalid gains at set-up with a clear error") {
  auto g = gainsWith(1.0, 1.0);
  g.Zq(0, 0) = -1.0;
  CHECK_THROWS_AS(NonlinearSubspaceRenderer<Model>(test::exoModel(), g), Error);
  g = gainsWith(std::nan(""), 1.0);
  CHECK_THROWS_AS(StandardRenderer<Model>(test::exoModel(), g), Error);
  g = gainsWith(1.0, 1.0);
  g.force_limit(0) = 0.0;
  CHECK_THROWS_AS(LinearizedSubspaceRenderer<Model>(test::exoModel(), g), Error);
}

namespace {
// Work done on the finger over `loops` closed flexion cycles (an ellipse in joint-angle space,
// driven by the finger, not by the device), proxy held still inside the range, sampled at rate_hz.
template <class Renderer>
double workOverClosedLoops(Renderer& r, double rate_hz, int loops) {
  const Vec2 centre(0.75, 0.85), radius(0.35, 0.4);  // rad, inside MCP 0-90 deg, PIP 0-100 deg
  const Vec2 proxy(0.9, 0.6);
  PassivityObserver<1> obs;
  const int n = static_cast<int>(rate_hz * loops);  // one loop per second
  Vec<1> tau;
  Vec2 q;
  for (int k = 0; k <= n; ++k) {
    const double phase = 2.0 * M_PI * k / rate_hz;
    const Vec2 x(centre(0) + radius(0) * std::cos(phase), centre(1) + radius(1) * std::sin(phase));
    REQUIRE(test::exoModel().inverse(x, q));
    REQUIRE(r.tick(q, proxy, tau) == Fault::kNone);
    obs.update(Vec<1>(q(0)), tau);
  }
  return obs.energyOut();
}
}  // namespace

TEST_CASE("exo energy: the subspace proxy generates no energy over closed finger motions, the "
          "standard method does") {
  // With the proxy still, the nonlinear subspace proxy is a spring towards a fixed q*_a: conservative
  // in q_a, so the work over a closed cycle is only the zero-order-hold term k/2 sum(dl^2), which
  // vanishes as the rate grows (divides by ~10 per decade). The standard method's force depends on
  // the unactuated joint too, so over the same cycles it pumps a rate-independent amount of energy in
  // one direction or the other (the "not always passive in practice" of paper 000).
  const auto gains = gainsWith(1.0 / (48.3 * 48.3), 1000.0);  // Z_q = 1 kN/m; Z_x matched as in Fig. 4
  auto scaled = gains;
  scaled.Zx *= 1000.0;
  NonlinearSubspaceRenderer<Model> sub1(test::exoModel(), gains), sub10(test::exoModel(), gains);
  StandardRenderer<Model> std1(test::exoModel(), scaled), std10(test::exoModel(), scaled);
  const double w_sub_1k = workOverClosedLoops(sub1, 1000.0, 5);
  const double w_sub_10k = workOverClosedLoops(sub10, 10000.0, 5);
  const double w_std_1k = workOverClosedLoops(std1, 1000.0, 5);
  const double w_std_10k = workOverClosedLoops(std10, 10000.0, 5);
  std::cout << "stress: exo energy over 5 closed cycles [J]: subspace " << w_sub_1k << " (1 kHz), " << w_sub_10k
            << " (10 kHz); standard " << w_std_1k << " (1 kHz), " << w_std_10k << " (10 kHz)\n";
  // ZOH term: positive, and ~10x smaller at 10x the rate (allow 8x-12x).
  CHECK(w_sub_1k >= 0.0);
  CHECK(w_sub_10k * 8.0 < w_sub_1k);
  CHECK(w_sub_10k * 12.0 > w_sub_1k);
  // The standard method's cycle work does not vanish with the rate: it is a property of the force
  // field, not of sampling (within 20 % between the two rates), and it dominates the ZOH term.
  CHECK(std::abs(w_std_10k) > 10.0 * std::abs(w_sub_10k));
  CHECK(w_std_10k == Approx(w_std_1k).epsilon(0.2));
}

TEST_CASE("exo renderers never refuse a reachable proxy from a state inside the working range") {
  // The refusals above come from out-of-range or non-finite input; inside the range every method
  // must render (a fault here would silently drop forces in ordinary use).
  stress::AdversarialSource src(7);
  const auto gains = gainsWith(1e-3, 100.0);
  StandardRenderer<Model> a(test::exoModel(), gains);
  NullSpaceRenderer<Model> b(test::exoModel(), gains);
  LinearizedSubspaceRenderer<Model> c(test::exoModel(), gains);
  NonlinearSubspaceRenderer<Model> d(test::exoModel(), gains);
  const auto& xlo = test::exoModel().taskLower();
  const auto& xhi = test::exoModel().taskUpper();
  Vec<1> tau;
  Vec2 q;
  const int n = 2000 * stress::scale();
  for (int i = 0; i < n; ++i) {
    const Vec2 x(src.uniform(xlo(0), xhi(0)), src.uniform(xlo(1), xhi(1)));
    const Vec2 xp(src.uniform(xlo(0), xhi(0)), src.uniform(xlo(1), xhi(1)));
    REQUIRE(test::exoModel().inverse(x, q));
    CHECK(a.tick(q, xp, tau) == Fault::kNone);
    CHECK(b.tick(q, xp, tau) == Fault::kNone);
    CHECK(c.tick(q, xp, tau) == Fault::kNone);
    CHECK(d.tick(q, xp, tau) == Fault::kNone);
  }
  std::cout << "stress: exo in-range: " << n << " cases per method, no refusals\n";
}

TEST_CASE("exo renderers refuse a state the model flags outside its working range: fault, zero force") {
  // Outside the stroke or the finger's range the model's forward() is only a continuation (clamped
  // closures): rendering from it would push on a fictitious finger. Every method must refuse.
  const auto gains = gainsWith(1e-3, 100.0);
  StandardRenderer<Model> a(test::exoModel(), gains);
  NullSpaceRenderer<Model> b(test::exoModel(), gains);
  LinearizedSubspaceRenderer<Model> c(test::exoModel(), gains);
  NonlinearSubspaceRenderer<Model> d(test::exoModel(), gains);
  const Vec2 lo = test::exoModel().jointLimits().lower, hi = test::exoModel().jointLimits().upper;
  const Vec2 mid = 0.5 * (lo + hi);
  const Vec2 proxy = 0.5 * (test::exoModel().taskLower() + test::exoModel().taskUpper());
  int refused = 0;
  for (const Vec2& q : {Vec2(hi(0) + 1e-6, mid(1)), Vec2(lo(0) - 1e-6, mid(1)), Vec2(hi(0) + 0.05, mid(1)),
                        Vec2(mid(0), hi(1) + 0.3), Vec2(mid(0), lo(1) - 0.3)}) {
    REQUIRE_FALSE(test::exoModel().inWorkingRange(q));
    const auto refuses = [&](auto& renderer) {
      Vec<1> tau = Vec<1>::Constant(1.0);
      return renderer.tick(q, proxy, tau) == Fault::kOutOfRange && tau.isZero(0.0) &&
             renderer.last().fault == Fault::kOutOfRange;
    };
    CHECK(refuses(a));
    CHECK(refuses(b));
    CHECK(refuses(c));
    CHECK(refuses(d));
    ++refused;
  }
  // Back inside, every method renders again (the refusal leaves no state behind).
  Vec2 q;
  REQUIRE(test::exoModel().inverse(test::exoModel().taskLower() + Model::TaskVector::Constant(0.3), q));
  Vec<1> tau;
  CHECK(a.tick(q, proxy, tau) == Fault::kNone);
  CHECK(b.tick(q, proxy, tau) == Fault::kNone);
  CHECK(c.tick(q, proxy, tau) == Fault::kNone);
  CHECK(d.tick(q, proxy, tau) == Fault::kNone);
  CHECK(tau(0) != 0.0);
  CHECK(refused == 5);
}
