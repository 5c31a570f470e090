// Paper 000's Fig. 4 motion through the exoskeleton's own policy (its DevicePolicy factory, the
// hardware path's sensing, command delay and force loop), judged by the referee from the plant's
// truth: the energy each method gives the finger, split into the field's own work and the sampled
// hold's share (exo_fig4.hpp); and the policy's set-up choices the experiment makes (method, Z_x).
#include <catch2/catch.hpp>
#include <cmath>
#include <memory>

#include "device_servo_renderers.hpp"
#include "params.hpp"
#include "renderer_fixtures.hpp"
#include "uhaptics/backends/board_catalog.hpp"
#include "uhaptics/experiments/exo_fig4.hpp"
#include "uhaptics/renderers/exo_finger_policy.hpp"

using namespace uhaptics;

namespace {

exo::Fig4EnergyOptions productPath() {
  const DeviceDefinition& device = findDevice("exo");
  exo::Fig4EnergyOptions e;
  e.spec = boardSpec(device, test::paramsDir());
  e.servo_period_s = 1.0 / e.spec.servo_rate_hz;
  e.board_period_s = 1.0 / e.spec.sample_rate_hz;
  e.command_delay = ServoLoop::kCommandDelayPeriods;
  e.make_policy = [&device] { return makeDevicePolicy(device, test::paramsDir()); };
  return e;
}

const exo::Fig4Energy& fig4Motion() {
  static const exo::Fig4Energy e = exo::runFig4Energy(test::exoModel(), exo::Fig4Options{}, productPath());
  return e;
}

const exo::Fig4Energy& loop() {
  static const exo::Fig4Energy e = [] {
    exo::Fig4EnergyOptions options = productPath();
    options.loop = true;
    return exo::runFig4Energy(test::exoModel(), exo::Fig4Options{}, options);
  }();
  return e;
}

const exo::Fig4MethodEnergy& of(const exo::Fig4Energy& e, int method) { return e.methods[static_cast<std::size_t>(method)]; }

// The closed form delta S is first order in delta; every run here meets it within 0.7 % (to 4 digits without
// the force loop, whose smoothing of the held steps is what the first order leaves out). 5 % leaves
// the second-order terms room: (omega delta)^2 is about 0.4 % at 7 ms and this motion's 1 Hz content.
constexpr double kHoldTolerance = 0.05;

}  // namespace

TEST_CASE("a held, delayed, lagging force acts delta late, as the referee reads it") {
  // Held over T without a force loop: half a period, plus the command delay.
  CHECK(exo::heldForceDelay(0.002, 0, 0.001, 0.0) == Approx(0.001));
  CHECK(exo::heldForceDelay(0.002, 1, 0.001, 0.0) == Approx(0.003));
  // Through a force loop stepped at h = 1 ms (tau = 5 ms): d T + h / 2 + h / (e^(h/tau) - 1).
  CHECK(exo::heldForceDelay(0.002, 1, 0.001, 0.005) == Approx(0.002 + 0.0005 + 0.001 / std::expm1(0.2)).epsilon(1e-12));
  // A finely stepped loop trails by its time constant, tau.
  CHECK(exo::heldForceDelay(1e-6, 0, 1e-6, 0.005) == Approx(0.005).epsilon(1e-6));
}

TEST_CASE("Fig. 4 motion through the device's policy: its own policy at the protocol's normalization, no faults") {
  const exo::Fig4Energy& e = fig4Motion();
  static const exo::Fig4Result protocol = exo::runFig4(test::exoModel(), exo::Fig4Options{});
  CHECK(e.zx == Approx(protocol.zx).epsilon(1e-12));  // Z_x = Z_q / avg(|J_a|)^2 over the same motion
  CHECK(e.closure_rad < 1e-9);                        // closed: two MCP cycles, three PIP cycles
  CHECK(e.delay_s == Approx(exo::heldForceDelay(0.002, 1, 0.001, test::exoModel().forceLoopTimeConstant())));
  for (const exo::Fig4Energy* run : {&fig4Motion(), &loop()}) {
    for (int m : exo::kPolicyMethods) {
      INFO(exo::methodName(m) << (run->options.loop ? ", loop" : ", Fig. 4 motion"));
      CHECK(of(*run, m).forward.faults + of(*run, m).backward.faults + of(*run, m).fine_forward.faults +
                of(*run, m).fine_backward.faults == 0);
      CHECK(of(*run, m).forward.max_abs_force_N > 0.0);
      CHECK(of(*run, m).forward.max_abs_force_N < 0.5 * test::exoModel().effortLimits()(0));  // never clamped
    }
  }
  // The policy computes the paper's forces: on the same frames (ideal sensors, 500 Hz) and the same
  // Z_x, the standard and null-space methods' largest commands are the protocol's.
  for (int m : {exo::kStandard, exo::kNullSpace})
    CHECK(of(e, m).forward.max_abs_force_N == Approx(protocol.summary[m].max_abs_force).epsilon(1e-9));
}

TEST_CASE("Fig. 4 motion, referee: every method's energy is its sampled hold's, delta S, to first order") {
  for (const exo::Fig4Energy* run : {&fig4Motion(), &loop()}) {
    for (int m : exo::kPolicyMethods) {
      const exo::Fig4MethodEnergy& r = of(*run, m);
      const double closed = r.holdClosedForm_mJ(run->delay_s);
      INFO(exo::methodName(m) << (run->options.loop ? ", loop" : ", Fig. 4 motion") << ": hold share "
                              << r.holdShare_mJ() << " mJ, delta S " << closed << " mJ");
      CHECK(closed > 0.0);  // every field here stiffens against the motion: the hold gives energy
      CHECK(r.holdShare_mJ() == Approx(closed).epsilon(kHoldTolerance));
      // The fine run leaves the hold a 300th of it (delta 25 us against 7 ms).
      const double fine_hold = 0.5 * (r.fine_forward.generated_mJ + r.fine_backward.generated_mJ);
      CHECK(std::abs(fine_hold) < 0.01 * closed);
    }
  }
}

TEST_CASE("Fig. 4 motion, referee: the subspace proxy gives no energy beyond the sampled hold, the standard "
          "method only the hold's on this motion") {
  const exo::Fig4Energy& e = fig4Motion();
  const exo::Fig4MethodEnergy& sub = of(e, exo::kSubspaceNonlinear);
  const exo::Fig4MethodEnergy& standard = of(e, exo::kStandard);
  WARN("Fig. 4 motion, energy given to the finger: subspace " << sub.forward.generated_mJ << " mJ (delta S "
       << sub.holdClosedForm_mJ(e.delay_s) << "), standard " << standard.forward.generated_mJ << " mJ (delta S "
       << standard.holdClosedForm_mJ(e.delay_s) << "), null-space " << of(e, exo::kNullSpace).forward.generated_mJ
       << " mJ");
  // Issue 39's claim, stated up to the sampled hold: the subspace proxy at or below zero beyond it...
  CHECK(sub.forward.generated_mJ <= (1.0 + kHoldTolerance) * sub.holdClosedForm_mJ(e.delay_s));
  CHECK(std::abs(sub.fieldWork_mJ()) < 1e-6 * sub.holdClosedForm_mJ(e.delay_s));
  // ...and the standard method positive, but only by its hold: the motion's path back retraces its
  // path out, so its field does no net work here either.
  CHECK(standard.forward.generated_mJ > 0.0);
  CHECK(std::abs(standard.fieldWork_mJ()) < 1e-6 * standard.holdClosedForm_mJ(e.delay_s));
}

TEST_CASE("Fig. 4 loop, referee: the baselines' fields do work round it, positive one way and negative the "
          "other, the subspace proxy's none") {
  const exo::Fig4Energy& e = loop();
  CHECK(e.closure_rad < 1e-9);
  const exo::Fig4MethodEnergy& sub = of(e, exo::kSubspaceNonlinear);
  // A spring in l_x: its work round any closed path is zero (the fine runs' difference is round-off
  // and the second order of 25 us).
  CHECK(std::abs(sub.fieldWork_mJ()) < 1e-3 * sub.holdClosedForm_mJ(e.delay_s));
  CHECK(sub.backward.generated_mJ <= (1.0 + kHoldTolerance) * sub.holdClosedForm_mJ(e.delay_s));
  CHECK(sub.forward.generated_mJ <= (1.0 + kHoldTolerance) * sub.holdClosedForm_mJ(e.delay_s));
  for (int m : {exo::kStandard, exo::kNullSpace}) {
    const exo::Fig4MethodEnergy& r = of(e, m);
    const double hold = r.holdClosedForm_mJ(e.delay_s);
    INFO(exo::methodName(m) << ": W " << r.fieldWork_mJ() << " mJ, forward " << r.forward.generated_mJ
                            << " mJ, backward " << r.backward.generated_mJ << " mJ, delta S " << hold << " mJ");
    // The field's work round the loop (measured: -0.75 mJ standard, -0.48 mJ null-space, with the
    // PIP ahead) is many times the hold's, and the product's runs show it: the same at 500 Hz.
    CHECK(std::abs(r.fieldWork_mJ()) > 10.0 * hold);
    CHECK(0.5 * (r.forward.generated_mJ - r.backward.generated_mJ) ==
          Approx(r.fieldWork_mJ()).epsilon(kHoldTolerance));
    // On this linkage, traced with the PIP a quarter cycle behind (backward), the loop gives the
    // finger energy far beyond the hold; the other way the finger gives the device energy.
    CHECK(r.backward.generated_mJ - hold > 10.0 * hold);
    CHECK(r.forward.generated_mJ < 0.0);
  }
}

TEST_CASE("the exoskeleton's policy from its factory: method and coupling stiffness are set-up choices") {
  std::unique_ptr<DevicePolicy> made = makeDevicePolicy(findDevice("exo"), test::paramsDir());
  auto* policy = dynamic_cast<ExoFingerPolicy*>(made.get());
  REQUIRE(policy != nullptr);
  CHECK(policy->method() == ExoFingerPolicy::Method::kSubspaceProxy);  // the product's default
  CHECK(policy->name() == NonlinearSubspaceRenderer<ExoFingerModel>::kName);
  policy->setMethod(ExoFingerPolicy::Method::kNullSpace);
  CHECK(policy->name() == NullSpaceRenderer<ExoFingerModel>::kName);
  policy->setMethod(ExoFingerPolicy::Method::kStandard);
  CHECK(policy->name() == StandardRenderer<ExoFingerModel>::kName);
  // Z_q is Z_x seen at the actuator: it scales with Z_x.
  const double zq = policy->actuatorStiffness();
  policy->setCouplingStiffness(2.0 * policy->couplingStiffness());
  CHECK(policy->actuatorStiffness() == Approx(2.0 * zq).epsilon(1e-12));
  for (double bad : {0.0, -1.0, std::nan(""), HUGE_VAL}) CHECK_THROWS_AS(policy->setCouplingStiffness(bad), Error);
}
