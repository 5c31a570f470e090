// The TAU-class 6-DoF parallel desktop device (paper 001): 6 actuated joints, stiff contacts
// rendered by the LQR position-control wall.
#include "uhaptics/backends/board_catalog.hpp"
#include "uhaptics/backends/tau_plant.hpp"
#include "uhaptics/models/param_file.hpp"
#include "uhaptics/models/tau_model.hpp"

namespace uhaptics::devices::tau {

DeviceDefinition definition() {
  DeviceDefinition d;
  d.title = "TAU";
  d.summary = "TAU-class 6-DoF parallel device, LQR wall on stiff contact (paper 001)";
  d.wire_code = 2;
  d.paper = {"001", "A Position-Control Based Approach to Haptic Rendering of Stiff Objects",
             "Wang, Feng, Andersson, IEEE Transactions on Haptics 2021"};
  d.published_link = {1000.0, "control at 1 kHz", 1000.0, "1 kHz sampling (the controller's)"};
  d.params_file = "tau.json";
  d.describe_board = [](const DeviceDefinition& self, const ParamFile& file, BoardSpec& spec) {
    const TauModel model = TauModel::fromParams(file);
    requireSameRate(file, "usb/servo_rate_hz", spec.servo_rate_hz, 1.0 / model.servoPeriod());
    const Vec6 limits = model.effortLimits();
    spec.descriptor = DeviceDescriptor::fromParams(file, wire::DeviceType{self.wire_code}, self.title, 6, 6, limits.data());
    for (int i = 0; i < 6; ++i) spec.position_resolution[i] = model.encoderResolution();
  };
  d.make_plant = [](const std::string& path) -> std::unique_ptr<BoardPlant> {
    return std::make_unique<TauBoardPlant>(TauModel::load(path), TauBoardPlant::Options{});
  };
  d.make_plant_stepped = [](const std::string& path, double step_period) -> std::unique_ptr<BoardPlant> {
    TauBoardPlant::Options options;
    options.step_period = step_period;
    return std::make_unique<TauBoardPlant>(TauModel::load(path), options);
  };
  d.make_userless_plant = [](const std::string& path, double step_period) -> std::unique_ptr<BoardPlant> {
    TauBoardPlant::Options options;
    options.hold_tool = false;
    options.step_period = step_period;
    return std::make_unique<TauBoardPlant>(TauModel::load(path), options);
  };
  d.hand_damping = HandModel{}.damping;
  return d;
}

}  // namespace uhaptics::devices::tau
