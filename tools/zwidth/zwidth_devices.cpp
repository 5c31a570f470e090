#include "zwidth_devices.hpp"

#include <array>
#include <cmath>
#include <limits>
#include <memory>

#include "device_servo_renderers.hpp"
#include "uhaptics/backends/board_catalog.hpp"
#include "uhaptics/backends/joint_io.hpp"
#include "uhaptics/core/fault.hpp"
#include "uhaptics/models/param_file.hpp"
#include "uhaptics/renderers/passive_policy.hpp"
#include "uhaptics/renderers/tau_policy.hpp"

namespace uhaptics {

namespace {

// The device's policy with no scene force: what it commands in free space.
class PolicyFreeSpace final : public experiments::FreeSpaceControl {
 public:
  PolicyFreeSpace(std::unique_ptr<DevicePolicy> policy, int actuators)
      : policy_(std::move(policy)), actuators_(actuators) {}
  void reset(int command_delay) override {
    policy_->reset(command_delay);
    ticks_ = 0;
  }
  bool efforts(const double* positions, const double* rates, bool first, double period, double* out) noexcept override {
    policy_->sense(SensedJoints{positions, rates, first}, state_);
    SceneInput input;
    input.dt = period;
    input.time = static_cast<double>(ticks_++) * period;
    input.seen_position = state_.position;
    if (policy_->render(input, out) != Fault::kNone) return false;
    for (int a = 0; a < actuators_; ++a)
      if (!std::isfinite(out[a])) return false;
    return true;
  }

 private:
  std::unique_ptr<DevicePolicy> policy_;
  int actuators_;
  SensedState state_;
  long ticks_ = 0;
};

// The joint's entry of a per-joint friction array in the parameter file; NaN when it has none.
double jointFriction(const ParamFile& file, const char* key, int joints, int joint) {
  if (!file.has(key)) return std::numeric_limits<double>::quiet_NaN();
  return file.numbers(key, static_cast<std::size_t>(joints), 0.0, std::numeric_limits<double>::max())[static_cast<std::size_t>(joint)];
}

}  // namespace

experiments::ZWidthDevice zwidthDevice(const DeviceDefinition& device, const std::string& params_dir, int joint) {
  experiments::ZWidthDevice d;
  d.name = device.name;
  d.spec = boardSpec(device, params_dir);
  const int actuators = d.spec.descriptor.actuators;
  if (joint < 0 || joint >= actuators)
    throw Error("Z-width: " + device.name + " actuates joints 0.." + std::to_string(actuators - 1) + ", not " +
                std::to_string(joint));
  d.joint = joint;
  const std::string path = params_dir + "/" + device.params_file;
  // The board's own plant where its step resolves the loop's period; the device's stepped plant
  // (make_plant_stepped) for a faster loop.
  const double board_period = 1.0 / d.spec.sample_rate_hz;
  d.make_plant = [make = device.make_plant, stepped = device.make_plant_stepped, path,
                  board_period](double period) -> std::unique_ptr<BoardPlant> {
    if (stepped && period < board_period * (1.0 - 1e-9)) return stepped(path, period);
    return make(path);
  };
  const DeviceDefinition* definition = &device;  // registrations live for the program
  d.make_free_space = [definition, params_dir, actuators]() -> std::unique_ptr<experiments::FreeSpaceControl> {
    return std::make_unique<PolicyFreeSpace>(makeDevicePolicy(*definition, params_dir), actuators);
  };
  const ParamFile file = ParamFile::load(path);
  d.param_viscous = jointFriction(file, "friction/viscous", d.spec.descriptor.joints, joint);
  d.param_coulomb = jointFriction(file, "friction/coulomb", d.spec.descriptor.joints, joint);
  return d;
}

std::vector<experiments::ZWidthDevice> registeredZWidthDevices(const std::string& params_dir, int joint) {
  std::vector<experiments::ZWidthDevice> devices;
  for (const DeviceDefinition* device : deviceDefinitions()) devices.push_back(zwidthDevice(*device, params_dir, joint));
  return devices;
}

experiments::TaskZWidthDevice taskZWidthDevice(const DeviceDefinition& device, const std::string& params_dir) {
  experiments::TaskZWidthDevice d;
  d.name = device.name;
  d.spec = boardSpec(device, params_dir);
  d.normal = Vec3::UnitZ();
  if (!device.make_userless_plant) {
    d.skip_note = "the user is position-driven (the finger moves the device): no force-source user, no Z-width";
    return d;
  }
  const std::string path = params_dir + "/" + device.params_file;
  // The plant in its board's steps where they resolve the loop's period, in the loop's otherwise.
  const double board_period = 1.0 / d.spec.sample_rate_hz;
  d.make_plant = [make = device.make_userless_plant, path, board_period](double period) {
    return make(path, period < board_period * (1.0 - 1e-9) ? period : 0.0);
  };
  d.hand_damping = device.hand_damping;
  const ParamFile file = ParamFile::load(path);
  const int joints = d.spec.descriptor.joints;
  for (int j = 0; j < joints; ++j)
    if (jointFriction(file, "friction/coulomb", joints, j) > 0.0) d.coulomb_friction = true;
  // A device whose policy can render with the LQR wall (paper 001's) is measured with both walls;
  // the LQR wall is designed for its model's servo period only.
  if (dynamic_cast<TauPolicy*>(makeDevicePolicy(device, params_dir).get())) {
    d.renderers = {"spring", "lqr"};
    d.native_rate_renderers = {"lqr"};
  }
  // The spring again with the passivity layer on, configured as the CHAI3D adapter configures it for
  // this board (passivity_max_damping unset): measured at the board's rate, the one its policy and
  // sensors are set up for. (spring + kObservedPassivitySuffix, the layer observing only, is run by
  // the layer's check, not swept.)
  d.renderers.push_back(std::string("spring") + experiments::kPassivitySuffix);
  d.native_rate_renderers.push_back(d.renderers.back());
  const DeviceDefinition* definition = &device;  // registrations live for the program
  d.make_policy = [definition, params_dir, spec = d.spec, make_rest_plant = d.make_plant](const std::string& renderer) {
    std::unique_ptr<DevicePolicy> policy = makeDevicePolicy(*definition, params_dir);
    const std::size_t base = renderer.find(experiments::kPassivitySuffix);
    if (auto* tau = dynamic_cast<TauPolicy*>(policy.get()))
      tau->setWallMode(renderer.compare(0, base, "lqr") == 0 ? TauPolicy::WallMode::kLqr
                                                             : TauPolicy::WallMode::kSpring);
    if (base == std::string::npos) return policy;
    std::array<double, wire::kMaxChannels> rest{};
    make_rest_plant(1.0 / spec.servo_rate_hz)->readJoints(rest.data());
    ScenePortPassivityOptions board = boardPassivityOptions(spec);
    board.enabled = renderer.compare(base, std::string::npos, experiments::kObservedPassivitySuffix) != 0;
    const PassivePolicy::Options options =
        passivePolicyOptions(*policy, rest.data(), spec.descriptor.joints, spec.descriptor.actuators, board);
    return std::unique_ptr<DevicePolicy>(
        std::make_unique<PassivePolicy>(std::move(policy), options, FigureRecorder::none()));
  };
  return d;
}

std::vector<experiments::TaskZWidthDevice> registeredTaskZWidthDevices(const std::string& params_dir) {
  std::vector<experiments::TaskZWidthDevice> devices;
  for (const DeviceDefinition* device : deviceDefinitions()) devices.push_back(taskZWidthDevice(*device, params_dir));
  return devices;
}

}  // namespace uhaptics
