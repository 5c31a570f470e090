#include "uhaptics/backends/joint_io.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "uhaptics/backends/board_emulator.hpp"
#include "uhaptics/protocol/libusb_transport.hpp"
#include "uhaptics/core/fault.hpp"

namespace uhaptics {
namespace {

using Channels = std::array<double, wire::kMaxChannels>;

// "sim": the simulated device stepped by the caller; commands pass the same safety stage as the
// servo loop's, so a renderer behaves identically on every backend.
class SimJointIo final : public JointIo {
 public:
  SimJointIo(BoardSpec spec, std::function<std::unique_ptr<BoardPlant>()> make_plant)
      : JointIo(std::move(spec), "sim"), make_plant_(std::move(make_plant)) {}

  void open() override {
    if (plant_) return;
    std::unique_ptr<BoardPlant> plant = make_plant_();
    const DeviceDescriptor& d = spec().descriptor;
    if (!plant || plant->jointCount() != d.joints || plant->actuatorCount() != d.actuators) {
      throw Error("simulated '" + d.name + "': the plant does not have the board's " + std::to_string(d.joints) +
                  " joints and " + std::to_string(d.actuators) + " actuators");
    }
    plant_ = std::move(plant);
  }
  void close() noexcept override {
    if (!plant_) return;
    const Channels zero{};
    plant_->applyCommand(zero.data());
    plant_.reset();
    time_us_ = 0.0;
  }
  bool isOpen() const noexcept override { return plant_ != nullptr; }

  bool read(double* positions) noexcept override {
    if (!plant_) return false;
    plant_->readJoints(positions);
    return true;
  }
  void command(const double* efforts) noexcept override {
    if (!plant_) return;
    const DeviceDescriptor& d = spec().descriptor;
    Channels u{};
    std::copy(efforts, efforts + d.actuators, u.begin());
    enforceEffortLimits(u.data(), d.actuators, d.effort_limit.data());
    plant_->applyCommand(u.data());
  }
  Fault advance(double dt) noexcept override {
    if (!plant_) return Fault::kNone;
    plant_->advance(dt);
    if (dt > 0.0 && std::isfinite(dt)) time_us_ = std::fmod(time_us_ + 1e6 * dt, 4294967296.0);  // wraps like a board clock
    return plant_->lastFault();
  }
  bool movesOnlyInAdvance() const noexcept override { return true; }
  bool readUserPoint(Vec3& position, Vec3& velocity) noexcept override {
    return plant_ && plant_->readUserPoint(position, velocity);
  }
  void setUserForce(const Vec3& force) noexcept override {
    if (plant_) plant_->setUserForce(force);
  }
  void setSceneForce(const Vec3& force) noexcept override {
    if (plant_) plant_->setSceneForce(force);
  }
  std::uint32_t sampleTimeUs() const noexcept override { return static_cast<std::uint32_t>(std::llround(time_us_) & 0xffffffffLL); }
  std::string describe() const override { return spec().descriptor.name + ", sim"; }

 private:
  std::function<std::unique_ptr<BoardPlant>()> make_plant_;
  double time_us_ = 0.0;
  std::unique_ptr<BoardPlant> plant_;
};

// "emulated" and "usb": a transport to a board and the real-time servo loop on it.
class ServoJointIo final : public JointIo {
 public:
  ServoJointIo(const DeviceDefinition& device, BoardSpec spec, std::string backend, ServoConfig servo, ServoRenderer* renderer,
               std::shared_ptr<BoardEmulatorControl> control, std::function<std::unique_ptr<BoardPlant>()> emulated_plant)
      : JointIo(std::move(spec), std::move(backend)), device_(device), servo_(servo), renderer_(renderer),
        control_(std::move(control)), emulated_plant_(std::move(emulated_plant)) {
    if (servo_.rate_hz == 0.0) servo_.rate_hz = this->spec().servo_rate_hz;
    if (servo_.board_watchdog_us == 0) servo_.board_watchdog_us = this->spec().board_watchdog_us;
    servo_.validate();
  }
  ~ServoJointIo() override { close(); }

  void open() override {
    if (loop_) return;
    const DeviceDescriptor& d = spec().descriptor;
    try {
      if (backend() == "usb") {
        transport_ = std::make_unique<LibusbTransport>(d);  // throws: no device found (lists what was)
      } else {
        plant_ = emulated_plant_ ? emulated_plant_() : device_.make_plant(spec().params_path);
        if (!plant_ || plant_->jointCount() != d.joints || plant_->actuatorCount() != d.actuators)
          throw Error("emulated '" + d.name + "': the plant does not have the board's " + std::to_string(d.joints) +
                      " joints and " + std::to_string(d.actuators) + " actuators");
        BoardEmulator::Config board;
        board.device = d.type;
        board.sample_rate_hz = spec().sample_rate_hz;
        board.effort_limit = d.effort_limit;
        auto emulator = std::make_unique<BoardEmulator>(board, *plant_);
        emulator_ = emulator.get();
        if (control_) control_->attach(emulator.get());
        transport_ = std::move(emulator);
      }
      loop_ = std::make_unique<ServoLoop>(d, *transport_, servo_, renderer_);
      loop_->connect();
      loop_->start();
    } catch (...) {
      close();  // nothing half-open: no thread, no claimed interface, nothing commanded
      throw;
    }
  }
  void close() noexcept override {
    if (loop_) loop_->stop();  // commands zero before the thread ends
    loop_.reset();
    if (control_) control_->attach(nullptr);
    emulator_ = nullptr;
    transport_.reset();
    plant_.reset();
    have_state_ = stopped_ = false;
  }
  bool isOpen() const noexcept override { return loop_ != nullptr; }

  bool read(double* positions) noexcept override {
    if (!loop_) return false;
    if (loop_->latest(snapshot_)) have_state_ = true;
    // A stopped loop's last snapshot may still say kRunning until its thread has ended.
    stopped_ = !loop_->running();
    if (stopped_ || !have_state_ || snapshot_.link != LinkState::kRunning || snapshot_.host_watchdog_tripped) return false;
    std::copy(snapshot_.position.begin(), snapshot_.position.begin() + snapshot_.joints, positions);
    return true;
  }
  void command(const double* efforts) noexcept override {
    if (!loop_) return;
    EffortRequest r;
    r.count = spec().descriptor.actuators;
    std::copy(efforts, efforts + r.count, r.effort.begin());
    loop_->request(r);  // the servo loop's safety stage checks it before it leaves the host
  }
  Fault advance(double) noexcept override { return Fault::kNone; }
  int commandDelayPeriods() const noexcept override { return ServoLoop::kCommandDelayPeriods; }
  bool readUserPoint(Vec3& position, Vec3& velocity) noexcept override {
    return emulator_ != nullptr && emulator_->readUserPoint(position, velocity);
  }
  void setUserForce(const Vec3& force) noexcept override {
    if (emulator_ != nullptr) emulator_->setUserForce(force);
  }
  void setSceneForce(const Vec3& force) noexcept override {
    if (emulator_ != nullptr) emulator_->setSceneForce(force);
  }
  LinkStatus linkStatus() const noexcept override {
    if (!loop_) return LinkStatus::kClosed;
    if (stopped_ || snapshot_.link == LinkState::kStopped) return LinkStatus::kStopped;
    if (!have_state_) return LinkStatus::kConnecting;
    switch (snapshot_.link) {
      case LinkState::kConnecting: return LinkStatus::kConnecting;
      case LinkState::kDisconnected: return LinkStatus::kDisconnected;
      case LinkState::kStopped: return LinkStatus::kStopped;
      case LinkState::kRunning: break;
    }
    return snapshot_.host_watchdog_tripped ? LinkStatus::kHostWatchdog : LinkStatus::kRunning;
  }
  std::uint32_t sampleTimeUs() const noexcept override { return snapshot_.sample_time_us[0]; }
  ServoLoop* servoLoop() noexcept override { return loop_.get(); }
  std::string describe() const override {
    return spec().descriptor.name + ", " + backend() + (transport_ ? std::string(" (") + transport_->describe() + ")" : "");
  }

 private:
  const DeviceDefinition& device_;
  ServoConfig servo_;
  ServoRenderer* renderer_;
  std::unique_ptr<BoardPlant> plant_;
  BoardEmulator* emulator_ = nullptr;  // transport_ on emulated
  std::unique_ptr<Transport> transport_;
  std::unique_ptr<ServoLoop> loop_;
  std::shared_ptr<BoardEmulatorControl> control_;
  std::function<std::unique_ptr<BoardPlant>()> emulated_plant_;
  DeviceSnapshot snapshot_;
  bool have_state_ = false, stopped_ = false;
};

}  // namespace

ScenePortPassivityOptions boardPassivityOptions(const BoardSpec& spec) {
  ScenePortPassivityOptions options;
  const int actuators = spec.descriptor.actuators;
  options.effort_limit.resize(actuators);
  options.resolution.resize(actuators);
  for (int i = 0; i < actuators; ++i) {
    const auto k = static_cast<std::size_t>(i);
    const double limit = spec.descriptor.effort_limit[k];
    options.effort_limit(i) = limit > 0.0 ? limit : std::numeric_limits<double>::infinity();
    options.resolution(i) = spec.position_resolution[k];
  }
  return options;
}

void JointRateEstimator::setResolution(const double* steps, int n) noexcept {
  resolution_.fill(0.0);
  n = std::clamp(n, 0, wire::kMaxChannels);
  for (int i = 0; i < n; ++i) resolution_[i] = std::isfinite(steps[i]) && steps[i] > 0.0 ? steps[i] : 0.0;
}

void JointRateEstimator::update(const double* positions, int n, std::uint32_t sample_us, double* rates) noexcept {
  n = std::clamp(n, 0, wire::kMaxChannels);
  if (!have_previous_) {
    rate_.fill(0.0);
    elapsed_ = 0.0;
    count_ = 0;
  } else if (sample_us == previous_us_) {
    std::copy(rate_.begin(), rate_.begin() + n, rates);  // no new sample: hold
    return;
  } else {
    // Unsigned difference: the elapsed time is right across the clock's wrap.
    elapsed_ += 1e-6 * static_cast<double>(static_cast<std::uint32_t>(sample_us - previous_us_));
  }
  head_ = (head_ + 1) % kHistory;
  std::copy(positions, positions + n, history_[head_].begin());
  time_[head_] = elapsed_;
  count_ = std::min(count_ + 1, kHistory);
  previous_us_ = sample_us;
  have_previous_ = true;
  // Per window length w: the sample w back and 1 / its age, shared by every joint.
  std::array<int, kHistory> back{};
  std::array<double, kHistory> inv_age{};
  for (int w = 1; w < count_; ++w) {
    back[w] = (head_ + kHistory - w) % kHistory;
    inv_age[w] = 1.0 / (elapsed_ - time_[back[w]]);
  }
  for (int i = 0; i < n && count_ > 1; ++i) {
    const double q = history_[head_][i];
    const double d = resolution_[i];
    // The longest window whose end-point line fits every sample inside it within d. A slope fits
    // sample j (dt_j back) when it lies in [(q - q_j - d) / dt_j, (q - q_j + d) / dt_j]: the
    // windows are tried longest-last, each against the intersection of its inner samples'
    // intervals, so the search is linear in the window.
    double slope = (q - history_[back[1]][i]) * inv_age[1];
    double lo = -std::numeric_limits<double>::infinity(), hi = std::numeric_limits<double>::infinity();
    for (int w = 2; d > 0.0 && w < count_; ++w) {
      const double rise = q - history_[back[w - 1]][i];
      lo = std::max(lo, (rise - d) * inv_age[w - 1]);
      hi = std::min(hi, (rise + d) * inv_age[w - 1]);
      const double candidate = (q - history_[back[w]][i]) * inv_age[w];
      if (candidate < lo || candidate > hi) break;
      slope = candidate;
    }
    rate_[i] = slope;
  }
  std::copy(rate_.begin(), rate_.begin() + n, rates);
}

const char* toString(LinkStatus s) noexcept {
  switch (s) {
    case LinkStatus::kClosed: return "closed";
    case LinkStatus::kRunning: return "running";
    case LinkStatus::kConnecting: return "connecting to the board (zero commanded)";
    case LinkStatus::kDisconnected: return "board disconnected (nothing sent, board unpowered)";
    case LinkStatus::kHostWatchdog: return "host watchdog: no valid state from the board (zero commanded)";
    case LinkStatus::kStopped: return "servo loop stopped (no current reading)";
  }
  return "unknown link status";
}

namespace {
using PlantFactory = std::function<std::unique_ptr<BoardPlant>()>;
// The factory's plants with the referee around them (none without a channel).
PlantFactory refereed(PlantFactory make_plant, std::shared_ptr<RefereeChannel> channel) {
  if (!channel) return make_plant;
  return [make_plant = std::move(make_plant), channel = std::move(channel)]() -> std::unique_ptr<BoardPlant> {
    std::unique_ptr<BoardPlant> plant = make_plant();
    if (!plant) return plant;
    return std::make_unique<RefereedPlant>(std::move(plant), channel);
  };
}
}  // namespace

std::unique_ptr<JointIo> makeSimJointIo(BoardSpec spec, PlantFactory make_plant, std::shared_ptr<RefereeChannel> referee) {
  if (!make_plant) throw Error("makeSimJointIo: no plant factory");
  return std::make_unique<SimJointIo>(std::move(spec), refereed(std::move(make_plant), std::move(referee)));
}

std::vector<std::string> jointIoBackends() { return {"sim", "emulated", "usb"}; }

std::unique_ptr<JointIo> makeJointIo(const std::string& device, const std::string& backend,
                                     const JointIoOptions& options) {
  const DeviceDefinition& definition = findDevice(device);  // throws naming the registered devices
  const auto backends = jointIoBackends();
  if (std::find(backends.begin(), backends.end(), backend) == backends.end())
    throw Error("unknown backend '" + backend + "' for device '" + device + "': use sim, emulated or usb");
  if (options.emulated_plant && backend != "emulated")
    throw Error("device '" + device + "': emulated_plant is given but the backend is " + backend);
  if (options.emulator_control && backend != "emulated")
    throw Error("device '" + device + "': emulator_control is given but the backend is " + backend +
                "; board faults can be injected only with the emulated backend");
  if (options.referee && backend == "usb")
    throw Error("device '" + device + "': a referee needs the simulated truth (sim or emulated), not usb");
  if (options.params_dir.empty()) throw Error("makeJointIo: params_dir is required (the device parameter files)");
  BoardSpec spec = options.params_file.empty() ? boardSpec(definition, options.params_dir)
                                               : boardSpecFromFile(definition, options.params_file);
  if (backend == "sim") {
    const std::string path = spec.params_path;
    return makeSimJointIo(std::move(spec), [&definition, path] { return definition.make_plant(path); }, options.referee);
  }
  PlantFactory emulated_plant = options.emulated_plant;
  if (backend == "emulated" && options.referee) {
    if (!emulated_plant) {
      const std::string path = spec.params_path;
      emulated_plant = [&definition, path] { return definition.make_plant(path); };
    }
    emulated_plant = refereed(std::move(emulated_plant), options.referee);
  }
  return std::make_unique<ServoJointIo>(definition, std::move(spec), backend, options.servo, options.renderer,
                                        options.emulator_control, std::move(emulated_plant));
}

}  // namespace uhaptics
