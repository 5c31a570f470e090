// The 4-DoF planar redundant haptic interface (paper 003): 4 actuated joints for a 2-D task, its
// self-motion steered by force-manipulability null-space control.
#include <limits>

#include "uhaptics/backends/board_catalog.hpp"
#include "uhaptics/backends/rhi_plant.hpp"
#include "uhaptics/models/param_file.hpp"
#include "uhaptics/models/planar_linkage_model.hpp"

namespace uhaptics::devices::rhi {

constexpr double kNotPublished = std::numeric_limits<double>::quiet_NaN();

DeviceDefinition definition() {
  DeviceDefinition d;
  d.title = "RHI planar";
  d.summary = "4-DoF planar redundant interface, J^T F + FME null-space control (paper 003)";
  d.wire_code = 3;
  d.published_link = {"003", kNotPublished, "no rate published", kNotPublished, "no rate published"};
  d.params_file = "rhi4.json";
  d.describe_board = [](const DeviceDefinition& self, const ParamFile& file, BoardSpec& spec) {
    const Rhi4Model model = Rhi4Model::load(spec.params_path, "rhi4");
    const Vec<4> limits = model.effortLimits();
    spec.descriptor = DeviceDescriptor::fromParams(file, wire::DeviceType{self.wire_code}, self.title, 4, 4, limits.data());
  };
  d.make_plant = [](const std::string& path) -> std::unique_ptr<BoardPlant> {
    return std::make_unique<RhiBoardPlant>(Rhi4Model::load(path, "rhi4"), RhiBoardPlant::Options{});
  };
  return d;
}

}  // namespace uhaptics::devices::rhi
