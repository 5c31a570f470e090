// The backend factory: one joint I/O for every device and backend (sim, emulated, usb), driven the
// same way by the device's renderer; "usb" without a board fails at open() with an actionable
// message and leaves nothing running.
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <deque>
#include <functional>
#include <iostream>
#include <thread>

#include "servo_rig.hpp"
#include "uhaptics/backends/joint_io.hpp"
#include "uhaptics/protocol/libusb_transport.hpp"
#include "uhaptics/core/fault.hpp"

using namespace uhaptics;
using namespace uhaptics::testing;

namespace {

JointIoOptions options() {
  JointIoOptions o;
  o.params_dir = kParamsDir;
  o.servo.realtime = false;
  o.servo.watchdog_periods = 50;  // the emulated run is threaded: a loaded machine must not trip it
  return o;
}

// Renders from a joint reading the way the servo loop would (positions + board time).
struct Driver {
  std::unique_ptr<DeviceServoRenderer> renderer;
  DeviceSnapshot snapshot;
  std::array<double, wire::kMaxChannels> efforts{};
  explicit Driver(const DeviceCase& c) : renderer(makeDeviceRenderer(c)) {
    snapshot.joints = c.device().joints;
    snapshot.actuators = c.actuators();
  }
  const double* render(const double* q, double t) {
    for (int i = 0; i < snapshot.joints; ++i) {
      snapshot.position[i] = q[i];
      snapshot.sample_time_us[i] = static_cast<std::uint32_t>(std::llround(t * 1e6));
    }
    snapshot.board_time_us = static_cast<std::uint32_t>(std::llround(t * 1e6));
    efforts.fill(0.0);
    renderer->render(snapshot, EffortRequest{}, efforts.data());
    return efforts.data();
  }
};

}  // namespace

TEST_CASE("joint I/O factory: names, backends and parameter files are checked", "[servo][jointio]") {
  CHECK(jointIoBackends() == std::vector<std::string>{"sim", "emulated", "usb"});
  CHECK_THROWS_WITH(makeJointIo("phantom", "sim", options()), Catch::Contains("use " + deviceNameList()));
  CHECK_THROWS_WITH(makeJointIo("tau", "serial", options()), Catch::Contains("use sim, emulated or usb"));
  JointIoOptions missing = options();
  missing.params_dir = "/nonexistent";
  CHECK_THROWS_AS(makeJointIo("tau", "sim", missing), Error);
  JointIoOptions injecting = options();
  injecting.emulator_control = std::make_shared<BoardEmulatorControl>();
  CHECK_THROWS_WITH(makeJointIo("tau", "usb", injecting), Catch::Contains("only with the emulated backend"));
  CHECK_THROWS_WITH(makeJointIo("tau", "sim", injecting), Catch::Contains("only with the emulated backend"));
  for (const DeviceCase& c : allDevices()) {
    const auto io = makeJointIo(c.definition->name, "sim", options());
    CHECK(io->spec().descriptor.product_id == c.device().product_id);
    CHECK(io->spec().descriptor.joints == c.device().joints);
    CHECK_FALSE(io->isOpen());
    double q[wire::kMaxChannels];
    CHECK_FALSE(io->read(q));  // nothing before open()
  }
}

TEST_CASE("joint I/O, sim: each device's renderer drives its simulation, commands held to the limits",
          "[servo][jointio]") {
  for (const DeviceCase& c : allDevices()) {
    INFO(c.name());
    const auto io = makeJointIo(c.definition->name, "sim", options());
    io->open();
    REQUIRE(io->isOpen());
    CHECK(io->describe() == c.name() + ", sim");
    CHECK(io->commandDelayPeriods() == 0);  // read after the step, commanded before the next
    Driver driver(c);
    double q[wire::kMaxChannels], q0[wire::kMaxChannels];
    REQUIRE(io->read(q0));
    const double dt = 1e-3;
    double largest_command = 0.0;
    bool finite = true;
    for (int k = 0; k < 2000; ++k) {
      REQUIRE(io->read(q));
      const double* u = driver.render(q, k * dt);
      for (int i = 0; i < c.actuators(); ++i) {
        finite = finite && std::isfinite(u[i]);
        largest_command = std::max(largest_command, std::abs(u[i]) / c.limit(i));
      }
      io->command(u);
      io->advance(dt);
    }
    REQUIRE(io->read(q));
    double drift = 0.0;
    for (int i = 0; i < c.device().joints; ++i) drift = std::max(drift, std::abs(q[i] - q0[i]));
    std::cout << c.name() << " (sim, 2 s through its renderer): largest |command| / limit " << largest_command
              << ", largest joint change " << drift << "\n";
    CHECK(finite);
    CHECK(driver.renderer->faults() == 0);
    CHECK(largest_command <= 1.0);
    CHECK(largest_command > 0.0);
    // The safety stage of the sim path: 10x the limit arrives scaled into the box.
    std::array<double, wire::kMaxChannels> over{};
    for (int i = 0; i < c.actuators(); ++i) over[i] = 10.0 * c.limit(i);
    io->command(over.data());
    io->advance(dt);
    io->close();
    CHECK_FALSE(io->isOpen());
    CHECK_FALSE(io->read(q));
  }
}

TEST_CASE("joint I/O, emulated: the same renderer through the servo loop and the board emulator",
          "[servo][jointio]") {
  for (const DeviceCase& c : allDevices()) {
    INFO(c.name());
    auto renderer = makeDeviceRenderer(c);
    JointIoOptions o = options();
    o.renderer = renderer.get();
    const auto io = makeJointIo(c.definition->name, "emulated", o);
    io->open();
    REQUIRE(io->isOpen());
    REQUIRE(io->servoLoop() != nullptr);
    CHECK(io->describe().find("in-process board emulator") != std::string::npos);
    CHECK(io->commandDelayPeriods() == 1);  // each STATE answers the previous period's COMMAND
    double q[wire::kMaxChannels];
    bool got = false;
    for (int k = 0; k < 5000 && !got; ++k) {  // the first STATE: milliseconds, seconds when sanitized
      got = io->read(q);
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    REQUIRE(got);
    const std::uint32_t first_sample_us = io->sampleTimeUs();
    // 100 periods of the servo thread (a few seconds at most, even in a sanitizer build).
    const auto t0 = std::chrono::steady_clock::now();
    while (io->servoLoop()->counters().ticks < 100 && std::chrono::steady_clock::now() - t0 < std::chrono::seconds(10))
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    REQUIRE(io->read(q));
    CHECK(io->sampleTimeUs() != first_sample_us);  // the board's sample clock, advancing
    CHECK(io->linkStatus() == LinkStatus::kRunning);
    io->servoLoop()->stop();  // counters and the renderer's fault count are final
    // A stopped loop's last reading is not current: read() says so instead of returning it.
    CHECK_FALSE(io->read(q));
    CHECK(io->linkStatus() == LinkStatus::kStopped);
    const ServoCounters k = io->servoLoop()->counters();
    CHECK(k.ticks >= 100);
    CHECK(k.frames_lost == 0);
    CHECK(k.frames_rejected == 0);
    if (k.host_watchdog_trips > 0) {
      // A VM stall under load can trip the 50-period watchdog: reported, not failed (the trip's
      // zero and resume are asserted in servo_loop_test.cpp).
      WARN(c.name() << ": " << k.host_watchdog_trips << " host watchdog trip(s), " << k.loop_stalls << " loop stall(s)");
    } else if (kRealTimeBounds) {
      CHECK(renderer->faults() == 0);
    }
    io->close();
    CHECK_FALSE(io->isOpen());
    CHECK(io->servoLoop() == nullptr);
  }
}

TEST_CASE("joint rate estimator: device-clock differences, repeated samples held, clock wrap", "[servo][jointio]") {
  JointRateEstimator rate;
  double q[2] = {0.1, -0.2}, qd[2] = {9.0, 9.0};
  rate.update(q, 2, 1000, qd);
  CHECK(qd[0] == 0.0);  // first reading: no rate yet
  CHECK(qd[1] == 0.0);
  q[0] = 0.1 + 2e-3;  // 2 rad/s over 1 ms
  q[1] = -0.2 - 5e-4;  // -0.5 rad/s
  rate.update(q, 2, 2000, qd);
  CHECK(qd[0] == Approx(2.0).epsilon(1e-9));
  CHECK(qd[1] == Approx(-0.5).epsilon(1e-9));
  // The same sample again (the board has not sampled since): the rate is held, not zeroed.
  rate.update(q, 2, 2000, qd);
  CHECK(qd[0] == Approx(2.0).epsilon(1e-9));
  // Across the 32-bit wrap: 0xFFFFFE0C -> 0x000001F4 is 1000 us.
  JointRateEstimator wrap;
  double p[1] = {0.0}, pd[1];
  wrap.update(p, 1, 0xFFFFFE0Cu, pd);
  p[0] = 1e-3;
  wrap.update(p, 1, 0x000001F4u, pd);
  CHECK(pd[0] == Approx(1.0).epsilon(1e-9));
  // Reset: the next reading starts over.
  wrap.reset();
  wrap.update(p, 1, 5000, pd);
  CHECK(pd[0] == 0.0);
}

TEST_CASE("joint rate estimator: quantized encoders, the adaptive window against the plain difference",
          "[servo][jointio]") {
  // The TAU's encoders (4096 counts per turn, truncated as the simulation and a counter do), 1 kHz.
  const double step = 2.0 * M_PI / 4096.0, dt = 1e-3;
  struct Errors {
    double rms = 0.0, worst = 0.0;
  };
  // RMS and worst rate error over 2 s of a joint moving as q(t), after the first 50 ms.
  const auto run = [&](double resolution, const std::function<double(double)>& q, const std::function<double(double)>& qd) {
    JointRateEstimator rate;
    rate.setResolution(&resolution, 1);
    Errors e;
    int n = 0;
    for (int k = 0; k < 2000; ++k) {
      const double t = k * dt;
      const double reading = std::floor(q(t) / step) * step;
      double estimate = 0.0;
      rate.update(&reading, 1, static_cast<std::uint32_t>(1000 * k), &estimate);
      if (k < 50) continue;
      const double error = estimate - qd(t);
      e.rms += error * error;
      e.worst = std::max(e.worst, std::abs(error));
      ++n;
    }
    e.rms = std::sqrt(e.rms / n);
    return e;
  };
  // Slow: 0.3 rad/s, a count every 5 ms. The plain difference reads 0 or 1.53 rad/s.
  const auto ramp = [](double t) { return 0.1 + 0.3 * t; };
  const auto ramp_rate = [](double) { return 0.3; };
  const Errors plain_slow = run(0.0, ramp, ramp_rate);
  const Errors foaw_slow = run(step, ramp, ramp_rate);
  INFO("slow ramp: plain rms " << plain_slow.rms << ", adaptive rms " << foaw_slow.rms << " worst " << foaw_slow.worst);
  CHECK(plain_slow.worst > 1.0);
  // Bound: one count over the longest window (the end points' truncation errors differ by < step).
  CHECK(foaw_slow.worst <= step / (JointRateEstimator::kMaxWindow * dt) * 1.5);
  // Fast: 0.2 rad at 5 Hz (peak 6.3 rad/s): short windows, little lag.
  const double w = 2.0 * M_PI * 5.0;
  const auto sine = [w](double t) { return 0.2 * std::sin(w * t); };
  const auto sine_rate = [w](double t) { return 0.2 * w * std::cos(w * t); };
  const Errors plain_fast = run(0.0, sine, sine_rate);
  const Errors foaw_fast = run(step, sine, sine_rate);
  INFO("5 Hz sine: plain rms " << plain_fast.rms << ", adaptive rms " << foaw_fast.rms << " worst " << foaw_fast.worst);
  CHECK(foaw_fast.rms < plain_fast.rms);
  // The price of the window is lag: a window fits while its curvature a (wT)^2 / 8 stays within one
  // count, and its secant is the rate at its middle, (wT) / 2 back: at most a sqrt(8 step / a) / 2.
  const double a = 0.2 * w * w;
  CHECK(foaw_fast.worst <= 1.25 * a * std::sqrt(8.0 * step / a) / 2.0);
  // A stop: the estimate falls to zero within the longest window.
  JointRateEstimator rate;
  rate.setResolution(&step, 1);
  double estimate = 0.0;
  for (int k = 0; k < 100; ++k) {
    const double t = k * dt;
    const double reading = std::floor(ramp(std::min(t, 0.05)) / step) * step;  // stops at 50 ms
    rate.update(&reading, 1, static_cast<std::uint32_t>(1000 * k), &estimate);
  }
  CHECK(std::abs(estimate) <= step / (JointRateEstimator::kMaxWindow * dt));
}

TEST_CASE("joint I/O, sim: the sample time is the simulated time", "[servo][jointio]") {
  const auto io = makeJointIo("tau", "sim", options());
  io->open();
  double q[wire::kMaxChannels];
  REQUIRE(io->read(q));
  CHECK(io->sampleTimeUs() == 0u);
  for (int k = 0; k < 250; ++k) io->advance(1e-3);
  REQUIRE(io->read(q));
  CHECK(io->sampleTimeUs() == 250000u);
  io->close();
}

TEST_CASE("joint I/O, usb without a board: open() fails saying what was found, nothing runs", "[servo][jointio]") {
  const bool board_present = [] {
    for (const auto& line : LibusbTransport::listDevices())
      if (line.find("1209:000") != std::string::npos) return true;
    return false;
  }();
  if (board_present) {
    WARN("a uhaptics board is attached: skipping the no-board check");
    return;
  }
  for (const DeviceCase& c : allDevices()) {
    INFO(c.name());
    const auto io = makeJointIo(c.definition->name, "usb", options());
    try {
      io->open();
      FAIL("open() succeeded without a board");
    } catch (const Error& e) {
      const std::string m = e.what();
      char ids[16];
      std::snprintf(ids, sizeof ids, "%04x:%04x", c.device().vendor_id, c.device().product_id);
      INFO(m);
      // "no device found (list what was found)", or libusb cannot see a bus at all.
      const bool absent = m.find(std::string("no USB device ") + ids) != std::string::npos &&
                          m.find("USB devices present:") != std::string::npos;
      CHECK((absent || m.find("libusb_init failed") != std::string::npos));
    }
    CHECK_FALSE(io->isOpen());
    CHECK(io->servoLoop() == nullptr);
    double q[wire::kMaxChannels];
    CHECK_FALSE(io->read(q));
    const std::array<double, wire::kMaxChannels> u{};
    io->command(u.data());  // harmless on a closed device
    io->close();
  }
}

namespace {

// The TAU's board plant under its free-space renderer (gravity compensation) with the command
// applied `delay` sample periods after the reading it was computed from, as the COMMAND/STATE
// exchange does (1 period, up to 2 with the sample's age). Returns the largest joint change in 3 s.
double tauDriftWithDelay(double rotational_damping, int delay) {
  TauBoardPlant::Options o;
  o.tool_rotational_damping = rotational_damping;
  o.end_stops = false;  // what is measured is the damping, not where the stops would catch the tool
  TauBoardPlant plant(TauModel::load(kParamsDir + "/tau.json"), o);
  const DeviceCase c = deviceCase("tau");
  Driver driver(c);
  std::array<double, wire::kMaxChannels> q0{}, q{};
  plant.readJoints(q0.data());
  std::deque<std::array<double, wire::kMaxChannels>> pipe(static_cast<std::size_t>(delay));
  const double dt = plant.model().servoPeriod();
  double drift = 0.0;
  for (int k = 0; k < static_cast<int>(std::lround(3.0 / dt)); ++k) {
    plant.readJoints(q.data());
    for (int i = 0; i < 6; ++i) drift = std::max(drift, std::abs(q[i] - q0[i]));
    const double* u = driver.render(q.data(), k * dt);
    pipe.emplace_back();
    std::copy(u, u + 6, pipe.back().begin());
    plant.applyCommand(pipe.front().data());
    pipe.pop_front();
    plant.advance(dt);
  }
  return drift;
}

}  // namespace

TEST_CASE("TAU board plant: the handle's damping keeps the pose under the exchange's command delay", "[servo][tau]") {
  // Measured: undamped 0.0015 rad with no delay, 0.38 rad with one period, diverging (renderer
  // faults) with two; damped 0.011 / 0.021 rad. 0.05 rad is twice the damped two-period figure.
  CHECK(tauDriftWithDelay(0.01, 0) < 0.01);
  CHECK(tauDriftWithDelay(0.01, 1) < 0.05);
  CHECK(tauDriftWithDelay(0.01, 2) < 0.05);
  // Without it the one-period delay alone moves the tool (the cause this test pins down).
  CHECK(tauDriftWithDelay(0.0, 1) > 0.2);
}
