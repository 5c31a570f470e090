// The finger exoskeleton module (paper 000): 1 linear actuator (l_x) and 1 sensed joint (q_B)
// driving a 2-joint virtual finger, rendered with the subspace proxy.
#include "uhaptics/backends/board_catalog.hpp"
#include "uhaptics/backends/exo_finger_plant.hpp"
#include "uhaptics/models/exo_finger_model.hpp"
#include "uhaptics/models/param_file.hpp"

namespace uhaptics::devices::exo_finger {

DeviceDefinition definition() {
  DeviceDefinition d;
  d.title = "finger exoskeleton";
  d.summary = "finger exoskeleton module, subspace proxy (paper 000)";
  d.wire_code = 1;
  d.paper = {"000", "Proxy-Based Haptic Rendering for Underactuated Haptic Devices",
             "Lobo, Sarac, Verschoor, Solazzi, Frisoli, Otaduy, World Haptics 2017"};
  d.published_link = {500.0, "USB link to the host at 500 Hz", 1000.0, "board samples at 1 kHz"};
  d.params_file = "exo_finger.json";
  d.describe_board = [](const DeviceDefinition& self, const ParamFile& file, BoardSpec& spec) {
    const ExoFingerModel model = ExoFingerModel::fromParams(file);
    requireSameRate(file, "usb/servo_rate_hz", spec.servo_rate_hz, model.hostRateHz());
    requireSameRate(file, "usb/sample_rate_hz", spec.sample_rate_hz, model.boardRateHz());
    const double limit = model.effortLimits()(0);
    spec.descriptor = DeviceDescriptor::fromParams(file, wire::DeviceType{self.wire_code}, self.title,
                                                   ExoFingerModel::kJoints, ExoFingerModel::kActuated, &limit);
  };
  d.make_plant = [](const std::string& path) -> std::unique_ptr<BoardPlant> {
    return std::make_unique<ExoFingerBoardPlant>(ExoFingerModel::load(path), ExoFingerBoardPlant::Options{});
  };
  return d;
}

}  // namespace uhaptics::devices::exo_finger
