#include "uhaptics/core/passivity_observer.hpp"

#include <catch2/catch.hpp>
#include <cmath>

using uhaptics::PassivityObserver;

// A 1-D user pushing into and out of a virtual wall rendered at 1 kHz, with the wall force computed
// from the position sampled at the start of each period (what a real servo does).
static double runWall(double k, double damping, double dt) {
  PassivityObserver<1> obs;
  double prev_x = 0.0;
  for (int i = 0; i <= 2000; ++i) {
    const double t = i * dt;
    const double x = 0.01 * std::sin(M_PI * t);  // in for 1 s, out for 1 s
    const double v = (x - prev_x) / dt;
    prev_x = x;
    const double f = x > 0.0 ? -k * x - damping * v : 0.0;
    obs.update(Eigen::Matrix<double, 1, 1>(x), Eigen::Matrix<double, 1, 1>(f));
  }
  return obs.energyOut();
}

TEST_CASE("passivity observer: a damped sampled wall absorbs energy over a cycle") {
  // Damping well above Colgate's bound b > K T / 2 dissipates more than sampling generates.
  CHECK(runWall(6000.0, 10.0, 1e-3) < 0.0);
}

TEST_CASE("passivity observer: an undamped sampled wall shows the energy sampling generates") {
  // With the position sampled at the start of each period, the force lags and the cycle returns more
  // energy than it took: the observer must see it (positive net output).
  CHECK(runWall(6000.0, 0.0, 1e-3) > 0.0);
}

TEST_CASE("passivity observer: exact work of a constant force") {
  PassivityObserver<2> obs;
  obs.update(Eigen::Vector2d(0, 0), Eigen::Vector2d(2, 1));
  obs.update(Eigen::Vector2d(0.5, -1), Eigen::Vector2d(0, 0));
  CHECK(obs.energyOut() == Approx(2 * 0.5 + 1 * -1.0));
  CHECK(obs.peakEnergyOut() == Approx(0.0));
}
