#pragma once
// The registered devices (device_definition.hpp) as the Z-width harness drives them: each device's
// simulated plant, its board spec (sensor resolution, effort limits), its rendering policy in free
// space under the wall (the TAU's gravity compensation, the planar linkages' null-space control),
// and the wall joint's friction as its parameter file states it.
#include <string>
#include <vector>

#include "uhaptics/backends/device_definition.hpp"
#include "uhaptics/experiments/task_zwidth.hpp"
#include "uhaptics/experiments/zwidth.hpp"

namespace uhaptics {

/// The device with its parameter file in params_dir, the wall on actuated joint `joint`. Throws Error
/// for a malformed file or a joint the device does not actuate.
experiments::ZWidthDevice zwidthDevice(const DeviceDefinition& device, const std::string& params_dir, int joint = 0);

/// Every registered device, in registration order, the wall on joint `joint` of each.
std::vector<experiments::ZWidthDevice> registeredZWidthDevices(const std::string& params_dir, int joint = 0);

/// The device for the task-space harness (task_zwidth.hpp): the plant a CHAI3D "sim" session makes
/// (no user of its own: cTauDevice's and cPlanarLinkageDevice's makeSimulatedPlant), its policy with
/// the renderer forced (the TAU: "spring" or "lqr" wall mode), the wall's normal +z in the device
/// frame (the user presses down: the TAU's table-top scenes, the planar devices' palpation axis, task
/// y = device -z), and the hand damping of the device's default simulated user (the TAU's b_h, the
/// planar grip's). Each device's spring is measured again with the passivity layer on
/// ("spring+passivity": PassivePolicy set up from the board spec and the parameter file's damping as
/// the CHAI3D adapter sets it up), at the board's servo rate. The exoskeleton's user is
/// position-driven: skip_note says so.
experiments::TaskZWidthDevice taskZWidthDevice(const DeviceDefinition& device, const std::string& params_dir);
std::vector<experiments::TaskZWidthDevice> registeredTaskZWidthDevices(const std::string& params_dir);

}  // namespace uhaptics
