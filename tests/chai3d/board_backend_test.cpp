// The CHAI3D devices on their board backends: "emulated" runs the whole hardware path (servo thread
// at the board's rate, wire protocol, watchdogs, safety stage, the board emulator on the device's
// own simulation and its own user) under the same device classes an application gets; "usb"
// without a board fails to open with the transport's message and leaves nothing running.
//
// The emulated boards' users hold the device (TAU: paper 001's hand, k_h = 40 N/m; RHI: an 800 N/m
// grip) or move it themselves (the exoskeleton's finger flexes and extends), so a constant
// application force must move the TAU and the RHI by about F / k and load the finger's actuator.
#include <catch2/catch.hpp>

#include <chrono>
#include <cmath>
#include <iostream>
#include <thread>

#include "chai3d.h"
#include "uhaptics/chai3d/CExoFingerDevice.hpp"
#include "uhaptics/chai3d/CRedundantPlanarDevice.hpp"
#include "uhaptics/chai3d/CTauDevice.hpp"
#include "uhaptics/core/sanitized_build.hpp"

using namespace chai3d;

namespace {

uhaptics::DeviceSelection boardSelection(const std::string& device, const std::string& backend) {
  uhaptics::DeviceSelection s;
  s.device = device;
  s.backend = backend;
  s.hand_enabled = false;  // the emulated board's own device and user (what these tests are about)
  return s;
}

struct Run {
  cVector3d start, end;  // device position [m] before and after
  double largest_output = 0.0;
  std::uint64_t faults = 0;
  std::uint64_t stale_input_ticks = 0;  // servo ticks whose application input was stale
  uhaptics::ServoCounters counters;
  // The statistics' servo_timing while the session ran and once it was closed (kept).
  bool timing_open = false, timing_closed = false;
  std::uint64_t timing_samples = 0;
  double nominal_period_us = 0.0, period_max_us = 0.0;
};

// The application's haptic loop in real time (about 1 kHz) for `seconds` with a constant force.
Run holdForce(const cUhapticsDevicePtr& device, const cVector3d& force, double seconds) {
  Run run;
  REQUIRE(device->open());
  REQUIRE(device->getServoLoop() != nullptr);
  device->getPosition(run.start);
  const auto t0 = std::chrono::steady_clock::now();
  while (std::chrono::steady_clock::now() - t0 < std::chrono::duration<double>(seconds)) {
    cVector3d p;
    device->getPosition(p);
    device->setForceAndTorqueAndGripperForce(force, cVector3d(0, 0, 0), 0.0);
    std::this_thread::sleep_for(std::chrono::microseconds(900));
  }
  device->getPosition(run.end);
  const uhaptics::SessionStatsSnapshot stats = device->getSessionStats();
  run.largest_output = stats.peak_output;
  run.faults = stats.faults;
  run.stale_input_ticks = stats.stale_input_ticks;
  run.timing_open = stats.has_servo_timing;
  device->getServoLoop()->stop();  // counters are final
  run.counters = device->getServoLoop()->counters();
  REQUIRE(device->close());
  CHECK(device->getServoLoop() == nullptr);
  const uhaptics::SessionStatsSnapshot closed = device->getSessionStats();
  run.timing_closed = closed.has_servo_timing;
  run.timing_samples = closed.servo_timing.samples;
  run.nominal_period_us = closed.servo_timing.nominal_period_us;
  run.period_max_us = closed.servo_timing.period.max_us;
  return run;
}

void checkLink(const Run& run) {
  CHECK(run.counters.ticks > 500);
  CHECK(run.counters.frames_lost == 0);
  CHECK(run.counters.frames_rejected == 0);
  CHECK(run.faults == 0);
  // The session's statistics say how the servo thread kept its period, and keep it after close().
  CHECK(run.timing_open);
  CHECK(run.timing_closed);
  // One period per servo tick after the first (a late wake-up is still one tick).
  CHECK(run.timing_samples + 1 == run.counters.ticks);
  CHECK(run.nominal_period_us == Approx(1000.0));
  CHECK(run.period_max_us >= 0.5 * run.nominal_period_us);
}

}  // namespace

TEST_CASE("board backend: TAU on the emulated board moves by F / k_h against paper 001's hand",
          "[chai3d][board]") {
  auto device = cTauDevice::create(boardSelection("tau", "emulated"));
  CHECK_THAT(device->getSpecifications().m_modelName, Catch::Contains("emulated"));
  const double force = 0.5;  // N along +y: 12.5 mm at k_h = 40 N/m
  const Run run = holdForce(device, cVector3d(0, force, 0), 3.0);
  const cVector3d d = run.end - run.start;
  const double along = d.y(), across = std::hypot(d.x(), d.z());
  std::cout << "tau, emulated board, 0.5 N for 3 s: " << run.counters.ticks << " servo ticks, " << 1e3 * along
            << " mm along the force, " << 1e3 * across << " mm across (F/k_h = 12.5 mm), "
            << run.stale_input_ticks << " ticks with stale input\n";
  checkLink(run);
  // F / k_h once the hand's damped oscillation (b_h = 3.6 N s/m) has settled; 20 % covers what is left of
  // it after 3 s on a loaded machine and the encoders' quantization.
  CHECK(along == Approx(force / 40.0).epsilon(0.2));
  // Sideways the handle is held by its rotational damping alone; the sanitizers slow the emulated
  // plant's step several-fold in the servo thread, and the late samples act as extra command delay,
  // which that damping does not cover (docs/hardware.md): 7-18 mm across in the ASan build, with or
  // without the referee, against under 1 mm in an optimized one. The along-force check above holds in both.
  if (!uhaptics::kSanitizedBuild) CHECK(across < along);
  CHECK(run.largest_output > 0.0);
  CHECK(run.largest_output <= 2.0);  // the joints' 2 N m
  // One period late, a saturated wall hands the spring only surfaces within the delayed rating.
  CHECK(device->getSpringLimit() == 2200.0);  // tau.json: max_linear_stiffness_delayed at 1 kHz
}

TEST_CASE("board backend: RHI on the emulated board moves by F / k against the grip, null space running",
          "[chai3d][board]") {
  auto device = cRedundantPlanarDevice::create(boardSelection("rhi", "emulated"));
  const double force = 2.0;  // N along device -z (paper 003's palpation direction u): 2.5 mm at 800 N/m
  const Run run = holdForce(device, cVector3d(0, 0, -force), 2.0);
  const cVector3d d = run.end - run.start;
  const double along = -d.z(), across = std::hypot(d.x(), d.y());
  std::cout << "rhi, emulated board, 2 N for 2 s: " << run.counters.ticks << " servo ticks, " << 1e3 * along
            << " mm along the force, " << 1e3 * across << " mm across (F/k = 2.5 mm)\n";
  checkLink(run);
  CHECK(along == Approx(force / 800.0).epsilon(0.1));  // static: the grip's F / k, settled within 2 s
  CHECK(across < 0.3 * along);
  CHECK(d.x() == 0.0);  // planar: device x is never sensed
}

TEST_CASE("board backend: finger exoskeleton on the emulated board, the finger moving by itself",
          "[chai3d][board]") {
  auto device = cExoFingerDevice::create(boardSelection("exo", "emulated"));
  double largest_actuator = 0.0;
  REQUIRE(device->open());
  cVector3d start, p;
  device->getPosition(start);
  double travel = 0.0;
  const auto t0 = std::chrono::steady_clock::now();
  while (std::chrono::steady_clock::now() - t0 < std::chrono::seconds(2)) {
    device->getPosition(p);
    travel = std::max(travel, (p - start).length());
    device->setForceAndTorqueAndGripperForce(cVector3d(0, 1.0, 0), cVector3d(0, 0, 0), 0.0);
    largest_actuator = std::max(largest_actuator, std::abs(device->getActuatorForce()));
    std::this_thread::sleep_for(std::chrono::microseconds(900));
  }
  const uhaptics::SessionStatsSnapshot stats = device->getSessionStats();
  device->getServoLoop()->stop();
  const uhaptics::ServoCounters counters = device->getServoLoop()->counters();
  REQUIRE(device->close());
  std::cout << "exo, emulated board, 1 N for 2 s: " << counters.ticks << " servo ticks, fingertip travel "
            << 1e3 * travel << " mm, largest actuator force " << largest_actuator << " N\n";
  CHECK(counters.ticks > 500);
  CHECK(counters.frames_lost == 0);
  CHECK(counters.frames_rejected == 0);
  CHECK(stats.faults == 0);
  CHECK(travel > 5e-3);  // paper 000's flexion-extension moves the fingertip centimetres per cycle
  CHECK(largest_actuator > 0.0);  // the proxy's pull reaches the actuator
  CHECK(largest_actuator <= device->getModel().effortLimits()(0));
}

TEST_CASE("board backend: usb without a board fails to open, says what was found, runs nothing",
          "[chai3d][board]") {
  for (const char* name : {"exo", "tau", "rhi"}) {
    INFO(name);
    const uhaptics::DeviceSelection s = boardSelection(name, "usb");
    cUhapticsDevicePtr device;
    if (std::string(name) == "exo") device = cExoFingerDevice::create(s);
    if (std::string(name) == "tau") device = cTauDevice::create(s);
    if (std::string(name) == "rhi") device = cRedundantPlanarDevice::create(s);
    CHECK(device->open() == C_ERROR);  // stderr names the ids sought and the USB devices present
    CHECK(device->getServoLoop() == nullptr);
    CHECK(device->setForceAndTorqueAndGripperForce(cVector3d(0, 1, 0), cVector3d(0, 0, 0), 0.0) == C_ERROR);
    CHECK(device->close());
  }
}
