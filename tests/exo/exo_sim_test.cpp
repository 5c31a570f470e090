// The simulated exoskeleton backend: trajectories, rates, force limit and force transmission.
#include "uhaptics/backends/exo_finger_sim.hpp"

#include <Eigen/LU>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>

#include "device_models.hpp"

using namespace uhaptics;
using Model = ExoFingerModel;

namespace {
std::string writeTemp(const std::string& name, const std::string& text) {
  const std::string path = std::string("/tmp/uhaptics_exo_test_") + name;
  std::ofstream(path) << text;
  return path;
}
}  // namespace

TEST_CASE("sim: runs a synthesized trajectory at the configured rate, inside the working range") {
  for (double rate : {500.0, 2000.0}) {
    ExoFingerSim sim(test::exoModel(), FingerTrajectory::synthesized(test::exoModel(), 2.0, 2.0, 1000.0), {rate, true});
    int steps = 0;
    while (!sim.finished()) {
      CHECK(sim.state().fault == Fault::kNone);
      CHECK(test::exoModel().inWorkingRange(sim.state().q, 1e-9));
      sim.command(Model::ActuatorVector(1.0));
      sim.step();
      ++steps;
    }
    CHECK(steps == static_cast<int>(std::lround(2.0 * rate)));
  }
}

TEST_CASE("sim: the force loop saturates at the actuator limit and rejects non-finite commands") {
  ExoFingerSim sim(test::exoModel(), FingerTrajectory::synthesized(test::exoModel(), 1.0, 1.0, 1000.0), {500.0, false});
  sim.command(Model::ActuatorVector(500.0));
  sim.step();
  CHECK(sim.state().force(0) == 50.0);
  sim.command(Model::ActuatorVector(-1e9));
  sim.step();
  CHECK(sim.state().force(0) == -50.0);
  sim.command(Model::ActuatorVector(std::numeric_limits<double>::quiet_NaN()));
  CHECK(sim.state().fault == Fault::kNonFiniteInput);
  sim.step();
  CHECK(sim.state().force(0) == 0.0);
  // With the lag on, a step command reaches 1 - exp(-T / tau) of its value after one period.
  ExoFingerSim lagged(test::exoModel(), FingerTrajectory::synthesized(test::exoModel(), 1.0, 1.0, 1000.0), {500.0, true});
  lagged.command(Model::ActuatorVector(10.0));
  lagged.step();
  CHECK(lagged.state().force(0) == Approx(10.0 * (1.0 - std::exp(-0.002 / test::exoModel().forceLoopTimeConstant()))));
}

TEST_CASE("sim: the actuator force reaches the finger through the linkage (virtual work)") {
  ExoFingerSim sim(test::exoModel(), FingerTrajectory::synthesized(test::exoModel(), 1.0, 1.0, 1000.0), {500.0, false});
  sim.command(Model::ActuatorVector(20.0));
  sim.step();
  const auto& s = sim.state();
  // tau_finger . dx = F dl_x for any small finger motion dx (q_B carries no torque).
  Model::Jacobian J;
  test::exoModel().jacobian(s.q, J);
  for (const Model::TaskVector& dx : {Model::TaskVector(1e-4, 0.0), Model::TaskVector(0.0, 1e-4), Model::TaskVector(-3e-5, 7e-5)}) {
    const Model::JointVector dq = J.inverse() * dx;
    CHECK(s.finger_torque.dot(dx) == Approx(20.0 * dq(0)).epsilon(1e-9));
  }
}

TEST_CASE("sim: recorded trajectories are read from CSV and bad files are refused clearly") {
  const std::string good = writeTemp("good.csv", "time_s,mcp_rad,pip_rad\n0,0.1,0.2\n0.5,0.5,0.6\n1.0,0.2,0.3\n");
  const FingerTrajectory t = FingerTrajectory::fromCsv(test::exoModel(), good);
  CHECK(t.duration() == 1.0);
  CHECK(t.at(0.25).isApprox(Model::TaskVector(0.3, 0.4)));
  CHECK(t.at(5.0).isApprox(Model::TaskVector(0.2, 0.3)));
  CHECK_THROWS_WITH(FingerTrajectory::fromCsv(test::exoModel(), writeTemp("hdr.csv", "t,a,b\n0,0,0\n")),
                    Catch::Contains("header"));
  CHECK_THROWS_WITH(FingerTrajectory::fromCsv(test::exoModel(), writeTemp("num.csv", "time_s,mcp_rad,pip_rad\n0,0.1,x\n1,0,0\n")),
                    Catch::Contains(":2:") && Catch::Contains("not a number"));
  CHECK_THROWS_WITH(FingerTrajectory::fromCsv(test::exoModel(), writeTemp("rng.csv", "time_s,mcp_rad,pip_rad\n0,0.1,0.1\n1,3.0,0.1\n")),
                    Catch::Contains("outside the working range"));
  CHECK_THROWS_WITH(FingerTrajectory::fromCsv(test::exoModel(), writeTemp("time.csv", "time_s,mcp_rad,pip_rad\n0,0.1,0.1\n0,0.2,0.1\n")),
                    Catch::Contains("increase"));
  CHECK_THROWS_WITH(FingerTrajectory::fromCsv(test::exoModel(), writeTemp("nan.csv", "time_s,mcp_rad,pip_rad\n0,nan,0.1\n1,0.2,0.1\n")),
                    Catch::Contains("not finite"));
  CHECK_THROWS_WITH(FingerTrajectory::fromCsv(test::exoModel(), "/nonexistent.csv"), Catch::Contains("cannot open"));
  CHECK_THROWS_WITH(ExoFingerSim(test::exoModel(), t, {1.0, true}), Catch::Contains("update_rate_hz"));
}

TEST_CASE("sim: a finger follows a fingertip path, reachable points exactly, others at the nearest pose") {
  const auto tip = [](const Model::TaskVector& x) {
    ExoFingerPoints p;
    test::exoModel().points(x, p);
    return p.fingertip;
  };
  // A circle of fingertip positions the finger reaches (poses inside the 5 % margin the path keeps).
  const Model::TaskVector lo = test::exoModel().taskLower(), span = test::exoModel().taskUpper() - test::exoModel().taskLower();
  const auto pose = [&](double t) {
    return Model::TaskVector(lo + span.cwiseProduct(Model::TaskVector(0.5 + 0.3 * std::cos(2.0 * M_PI * t / 2.0),
                                                                      0.5 + 0.3 * std::sin(2.0 * M_PI * t / 2.0))));
  };
  const auto reachable = FingerTrajectory::followingPath(test::exoModel(), [&](double t) { return tip(pose(t)); }, 2.0, 6.0, 50.0);
  CHECK(reachable.duration() == Approx(6.0).margin(0.02));
  double worst = 0.0;
  for (double t = 0.0; t <= 6.0; t += 0.02) {  // on the samples and between them (interpolated)
    worst = std::max(worst, (tip(reachable.at(t)) - tip(pose(t))).norm());
  }
  // Sample spacing: 2 s / 100 samples of a ~10 cm loop gives chords ~3 mm: interpolating the
  // angles between two exact samples departs from the circle by a fraction of a millimetre.
  CHECK(worst < 5e-4);

  // A target far outside the finger's reach: the pose whose fingertip is nearest, i.e. no pose of
  // a dense grid inside the same margin comes closer than 0.1 mm.
  const Vec2 far(1.0, 1.0);
  const auto unreachable = FingerTrajectory::followingPath(test::exoModel(), [&](double) { return far; }, 1.0, 1.0, 20.0);
  const double reached = (tip(unreachable.at(0.5)) - far).norm();
  double best = 1e9;
  for (int a = 0; a <= 100; ++a) {
    for (int b = 0; b <= 100; ++b) {
      const Model::TaskVector x = lo + 0.05 * span + 0.9 * span.cwiseProduct(Model::TaskVector(0.01 * a, 0.01 * b));
      best = std::min(best, (tip(x) - far).norm());
    }
  }
  CHECK(reached <= best + 1e-4);
  CHECK_THROWS_AS(FingerTrajectory::followingPath(test::exoModel(), [](double) { return Vec2(std::numeric_limits<double>::quiet_NaN(), 0.0); }, 1.0, 1.0, 20.0),
                  Error);
}
