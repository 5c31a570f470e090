#pragma once
// A device's joint I/O, whatever is behind it: the factory gives, for a device name and a backend,
//
//   "sim"       the device's simulated plant (devices/<device>/backend), stepped by the caller;
//   "emulated"  the same simulation behind the in-process board emulator, reached through the wire
//               protocol by the real-time servo loop (the whole hardware path without hardware);
//   "usb"       the device's controller board over libusb-1.0 and the servo loop.
//
// so a device class (e.g. the CHAI3D adapters) reads joints and writes efforts the same way for all
// three. Every effort passes the servo loop's safety stage (finite, scaled into the device's limits)
// before it reaches the device; the sim backend applies the same stage itself.
//
//   auto io = makeJointIo("tau", "usb", options);  // checks names and the parameter file
//   io->open();        // throws Error: no device found (and what was found), permission, version...
//   io->read(q); io->command(tau); io->advance(dt);  // per servo period, noexcept, no allocation
//   io->close();       // zero effort, stop, release (also in the destructor)
//
// read/command/advance belong to one thread (the caller's servo or haptic thread).
#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "uhaptics/backends/board_catalog.hpp"
#include "uhaptics/backends/board_emulator.hpp"
#include "uhaptics/backends/referee.hpp"
#include "uhaptics/backends/servo_loop.hpp"
#include "uhaptics/core/scene_port_passivity.hpp"

namespace uhaptics {

struct JointIoOptions {
  std::string params_dir;     // folder of the device parameter files (required)
  std::string params_file;    // overrides <params_dir>/<device file> (e.g. a lab's own USB ids)
  /// Servo loop settings (emulated, usb). rate_hz and board_watchdog_us of 0 take the file's values.
  ServoConfig servo = defaultServo();
  ServoRenderer* renderer = nullptr;  // optional, runs in the servo thread (emulated, usb)
  /// emulated only: the device behind the board emulator (e.g. a CHAI3D device's simulated plant,
  /// whose user is the caller's scripted hand); empty: the registered device's own plant and user.
  std::function<std::unique_ptr<BoardPlant>()> emulated_plant;
  /// sim and emulated: the referee's channel (referee.hpp). The simulated device is then observed
  /// from its truth every period and the figures published there; nothing of it reaches the caller's
  /// rendering. Refused with usb (no truth to judge by). Empty: no referee, nothing observed.
  std::shared_ptr<RefereeChannel> referee;
  /// emulated only: the handle through which a test or the soak run injects board faults into the
  /// open session (BoardEmulatorControl); refused with the other backends.
  std::shared_ptr<BoardEmulatorControl> emulator_control;

  static ServoConfig defaultServo() {
    ServoConfig c;
    c.rate_hz = 0.0;
    return c;
  }
};

/// What a joint I/O's link to its device is doing, as of its last read().
enum class LinkStatus : std::uint8_t {
  kClosed,        // not open
  kRunning,       // readings arrive, commands go out
  kConnecting,    // board found again (replugged, rebooted): handshake under way, zero commanded
  kDisconnected,  // the board is gone (unplugged): nothing sent, the board is unpowered
  kHostWatchdog,  // no valid STATE for the watchdog's periods (silent board, corrupt frames): zero
  kStopped,       // the servo loop was stopped (ServoLoop::stop()): no reading is current
};
const char* toString(LinkStatus s) noexcept;

class JointIo {
 public:
  virtual ~JointIo() = default;
  JointIo(const JointIo&) = delete;
  JointIo& operator=(const JointIo&) = delete;

  /// Connects (emulated/usb: find the board, handshake, start the servo thread). Throws Error with
  /// what to do; after a failure nothing runs and nothing is commanded.
  virtual void open() = 0;
  /// Zero effort, stop, release. Idempotent, never throws.
  virtual void close() noexcept = 0;
  virtual bool isOpen() const noexcept = 0;

  /// Newest joint positions (spec().descriptor.joints values). False when there is no valid
  /// reading: not open, link down, or the host watchdog holds the device at zero.
  virtual bool read(double* positions) noexcept = 0;
  /// Device-clock time [us] of the reading the last successful read() returned: the board's sample
  /// timestamp (emulated, usb; wraps at 2^32) or the simulated time (sim). Equal on two reads when
  /// no new sample arrived in between.
  virtual std::uint32_t sampleTimeUs() const noexcept = 0;
  /// Efforts (spec().descriptor.actuators values), held until the next call.
  virtual void command(const double* efforts) noexcept = 0;
  /// Servo periods between the reading a command is computed from and the period it starts to act
  /// in, for controllers that model the delay (the TAU's LQR wall): 0 when the device is read right
  /// after it moved and commanded before it moves again (sim), ServoLoop::kCommandDelayPeriods over
  /// the board protocol (emulated, usb).
  virtual int commandDelayPeriods() const noexcept { return 0; }
  /// sim: advances the simulation by dt and returns its fault. emulated/usb: nothing (the device
  /// runs on its own clock), kNone.
  virtual Fault advance(double dt) noexcept = 0;
  /// Whether the device moves only in advance() (sim): a reading taken right after it is the newest
  /// there will be until the next advance(). A board moves on its own clock instead.
  virtual bool movesOnlyInAdvance() const noexcept { return false; }
  /// sim and emulated: where a user the caller simulates holds the device, as it is
  /// (BoardPlant::readUserPoint, model task frame); false for usb and plants without such a point.
  virtual bool readUserPoint(Vec3& position, Vec3& velocity) noexcept {
    (void)position;
    (void)velocity;
    return false;
  }
  /// sim and emulated: the force [N] of a user the caller simulates on the end effector, in the
  /// device model's task frame (BoardPlant::setUserForce). usb: ignored (the user is a person).
  virtual void setUserForce(const Vec3& force) noexcept { (void)force; }
  /// sim and emulated with a referee: the force [N] the scene asks for this period, in the device
  /// model's task frame (BoardPlant::setSceneForce), for the referee alone. Otherwise ignored.
  virtual void setSceneForce(const Vec3& force) noexcept { (void)force; }

  /// Why read() has (or has no) reading: kRunning while read() succeeds.
  virtual LinkStatus linkStatus() const noexcept { return isOpen() ? LinkStatus::kRunning : LinkStatus::kClosed; }

  /// The servo loop behind emulated/usb (statistics, events); nullptr for sim or while closed.
  virtual ServoLoop* servoLoop() noexcept { return nullptr; }
  const BoardSpec& spec() const noexcept { return spec_; }
  const std::string& backend() const noexcept { return backend_; }
  /// e.g. "TAU, sim" or "TAU, usb 1209:0002 bus 1 addr 7".
  virtual std::string describe() const = 0;

 protected:
  JointIo(BoardSpec spec, std::string backend) : spec_(std::move(spec)), backend_(std::move(backend)) {}

 private:
  BoardSpec spec_;
  std::string backend_;
};

/// Joint rates from successive readings, the same on every backend, over the device's own sample
/// clock (not the host's wake-up time, which jitters), correct across the 32-bit clock wrap.
///
/// A quantized sensor (the TAU's encoders: 1.5 mrad a count) differenced over one 1 ms sample reads
/// 0 or 1.5 rad/s for a joint turning at 0.3 rad/s. With the sensor's resolution set
/// (setResolution), each joint's rate is a first-order adaptive window (Janabi-Sharifi, Hayward and
/// Chen, IEEE TCST 2000, end-fit FOAW): the slope of the longest window, up to kMaxWindow samples,
/// whose line through its end points passes within one resolution step of every sample inside it.
/// A fast joint gets a short window (little lag), a slow one a long window (little noise); a
/// joint with resolution 0 (an ideal sensor) gets the plain backward difference. A repeated sample
/// (same timestamp: the board has not sampled again yet) keeps the previous rate instead of reading
/// as a stop. The first reading after reset() gives zero rates. No allocation.
class JointRateEstimator {
 public:
  static constexpr int kMaxWindow = 20;  // samples: 20 ms at 1 kHz
  /// Per joint: the sensor's resolution (one quantization step) [rad or m]; 0: ideal. Keeps the history.
  void setResolution(const double* steps, int n) noexcept;
  void reset() noexcept {
    have_previous_ = false;
    count_ = 0;
  }
  /// n <= wire::kMaxChannels positions sampled at sample_us; writes n rates [unit/s].
  void update(const double* positions, int n, std::uint32_t sample_us, double* rates) noexcept;

 private:
  static constexpr int kHistory = kMaxWindow + 1;
  std::array<std::array<double, wire::kMaxChannels>, kHistory> history_{};  // positions, newest at head_
  std::array<double, kHistory> time_{};  // [s] since the first reading, same slots
  std::array<double, wire::kMaxChannels> resolution_{};
  std::array<double, wire::kMaxChannels> rate_{};
  int head_ = 0, count_ = 0;
  double elapsed_ = 0.0;
  std::uint32_t previous_us_ = 0;
  bool have_previous_ = false;
};

/// The passivity layer's options (scene_port_passivity.hpp) as the board states them: each actuated
/// joint's effort limit from the descriptor (infinity where it states none) and its sensor step
/// (the dead band of the displacement it brakes on). The inertia (passivePolicyOptions) is the
/// policy's. Set-up.
ScenePortPassivityOptions boardPassivityOptions(const BoardSpec& spec);

/// The "sim" joint I/O over a plant the caller makes (on open(), again after each close()): a device
/// class whose simulation needs a user or options of its own, or a test fixture. spec describes
/// the plant (counts, effort limits for the safety stage).
/// With a referee channel, each session's plant is refereed (RefereedPlant).
std::unique_ptr<JointIo> makeSimJointIo(BoardSpec spec, std::function<std::unique_ptr<BoardPlant>()> make_plant,
                                        std::shared_ptr<RefereeChannel> referee = nullptr);

/// Backends the factory offers, in the order to list them.
std::vector<std::string> jointIoBackends();
/// A registered device's name (device_definition.hpp); backend one of jointIoBackends(). Loads and validates the device's
/// parameter file; throws Error naming the valid choices for an unknown device or backend.
std::unique_ptr<JointIo> makeJointIo(const std::string& device, const std::string& backend,
                                     const JointIoOptions& options);

}  // namespace uhaptics
