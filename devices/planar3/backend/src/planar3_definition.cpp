// Paper 003's worked example (Section III-A.1): a 3-DoF planar serial arm, 0.25 m links, for a 2-D
// task, one degree of self-motion, steered by force-manipulability null-space control.
#include <limits>

#include "uhaptics/backends/planar_linkage_plant.hpp"
#include "uhaptics/models/planar_linkage_model.hpp"

namespace uhaptics::devices::planar3 {

constexpr double kNotPublished = std::numeric_limits<double>::quiet_NaN();
constexpr char kModel[] = "planar3";  // the parameter file's "device"

DeviceDefinition definition() {
  DeviceDefinition d;
  d.title = "planar 3-DoF arm";
  d.summary = "3-DoF planar arm (paper 003's example), J^T F + FME null-space control";
  d.wire_code = 4;
  d.paper = {"003", "Dynamic Reconfiguration of Redundant Haptic Interfaces for Rendering Soft and Hard Contacts",
             "Torabi, Zareinia, Sutherland, Tavakoli"};
  d.published_link = {kNotPublished, "no rate published", kNotPublished, "no rate published"};
  d.params_file = "planar3.json";
  d.describe_board = &describePlanarLinkageBoard<3, kModel>;
  d.make_plant = &makePlanarLinkagePlant<3, kModel>;
  d.make_userless_plant = &makeUserlessPlanarLinkagePlant<3, kModel>;
  d.hand_damping = PlanarLinkagePlant<3>::Options{}.hand_damping;
  return d;
}

}  // namespace uhaptics::devices::planar3
