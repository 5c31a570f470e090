// The 4-DoF planar redundant haptic interface (paper 003): 4 actuated joints for a 2-D task, its
// self-motion steered by force-manipulability null-space control.
#include <limits>

#include "uhaptics/backends/planar_linkage_plant.hpp"
#include "uhaptics/models/planar_linkage_model.hpp"

namespace uhaptics::devices::rhi {

constexpr double kNotPublished = std::numeric_limits<double>::quiet_NaN();
constexpr char kModel[] = "rhi4";  // the parameter file's "device"

DeviceDefinition definition() {
  DeviceDefinition d;
  d.title = "RHI planar";
  d.summary = "4-DoF planar redundant interface, J^T F + FME null-space control (paper 003)";
  d.wire_code = 3;
  d.paper = {"003", "Dynamic Reconfiguration of Redundant Haptic Interfaces for Rendering Soft and Hard Contacts",
             "Torabi, Zareinia, Sutherland, Tavakoli"};
  d.published_link = {kNotPublished, "no rate published", kNotPublished, "no rate published"};
  d.params_file = "rhi4.json";
  d.describe_board = &describePlanarLinkageBoard<4, kModel>;
  d.make_plant = &makePlanarLinkagePlant<4, kModel>;
  d.make_userless_plant = &makeUserlessPlanarLinkagePlant<4, kModel>;
  d.hand_damping = PlanarLinkagePlant<4>::Options{}.hand_damping;
  return d;
}

}  // namespace uhaptics::devices::rhi
