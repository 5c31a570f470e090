#pragma once
// What the host knows of one device, defined once in the device's own folder (devices/<device>/)
// and registered with one line in devices/CMakeLists.txt (uhaptics_add_device). Every list of
// devices (the protocol's device codes, the board catalog, the simulated plants, the servo tool,
// the CHAI3D registry, the CMake list the drop-in tests run) is derived from those registrations.
// docs/adding-a-device.md walks through adding one.
#include <array>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "uhaptics/backends/board_plant.hpp"
#include "uhaptics/protocol/device_descriptor.hpp"

namespace uhaptics {

class ParamFile;

/// The servo rates a device's rated wall stiffness is stated for (those the Z-width harness sweeps).
inline constexpr std::array<double, 4> kRatedServoRatesHz = {500.0, 1000.0, 2000.0, 4000.0};
/// A stiffness per kRatedServoRatesHz entry [N/m]; kUnrated: none stated.
using RatedStiffness = std::array<double, kRatedServoRatesHz.size()>;
inline constexpr RatedStiffness kUnrated = {std::numeric_limits<double>::quiet_NaN(),
                                            std::numeric_limits<double>::quiet_NaN(),
                                            std::numeric_limits<double>::quiet_NaN(),
                                            std::numeric_limits<double>::quiet_NaN()};

struct BoardSpec {
  DeviceDescriptor descriptor;
  double servo_rate_hz = 0.0;         // host <-> board exchange rate (the exoskeleton's USB: 500 Hz)
  double sample_rate_hz = 0.0;        // board sensor sampling
  std::uint32_t board_watchdog_us = 0;  // what the host configures with CONFIGURE
  std::string params_path;            // the file it came from
  /// Per joint: the sensor's resolution, one quantization step [rad or m] (the TAU's encoders:
  /// 2 pi / 4096); 0 for a sensor the simulation and the board treat as ideal. The rate estimator's
  /// noise bound (JointRateEstimator::setResolution).
  std::array<double, wire::kMaxChannels> position_resolution{};
  /// The stiffest spring wall at the tool [N/m] (CHAI3D's m_maxLinearStiffness) the device renders
  /// passively at each of kRatedServoRatesHz, with the command acting in the period it is computed
  /// from (the sim backend) and one period later (a board over the protocol): the parameter file's
  /// "stability" section, 0.8 of the boundary uhaptics-zwidth measures with the device's own policy
  /// (docs/stability.md). NaN where the file rates none (the exoskeleton's user is position-driven).
  RatedStiffness rated_stiffness = kUnrated;
  RatedStiffness rated_stiffness_delayed = kUnrated;
  /// The largest damping a scene should render at the tool [N s/m] and about it [N m s/rad]: the
  /// specification CHAI3D reports (m_maxLinearDamping, m_maxAngularDamping). The parameter file's
  /// "stability" section; 0 where it states none. (The passivity layer's cap comes from the policy's
  /// inertia, not from these: passive_policy.hpp.)
  double max_linear_damping = 0.0;
  double max_angular_damping = 0.0;
};

/// The paper whose method the device reproduces, written once here: the reproduction rows name it by
/// id, and the report and the docs' generated tables head those rows with its title.
struct PaperRef {
  std::string id;        // the papers folder's file prefix and the rows' paper column, e.g. "001"
  std::string title;     // the published title
  std::string citation;  // short: authors, venue, year
};

/// What the device's paper states about its link (NaN and "no rate published" where it says nothing),
/// for the servo tool's rows that set the rates measured here beside the paper's.
struct PublishedLink {
  double exchange_hz = 0.0;   // host <-> board exchange
  std::string exchange_text;
  double sampling_hz = 0.0;   // the board's sampling
  std::string sampling_text;
};

struct DeviceDefinition {
  /// Short name users select it by (UHAPTICS_DEVICE, --device), set by its registration line.
  std::string name;
  /// For messages and descriptors, e.g. "TAU".
  std::string title;
  /// One line: what it is and how it renders (listed by the tools and the CHAI3D registry).
  std::string summary;
  /// The protocol's device code in every frame, 1 .. wire::kMaxDeviceCode, unique.
  std::uint8_t wire_code = 0;
  /// The paper it reproduces.
  PaperRef paper;
  /// Its paper's statements about the link.
  PublishedLink published_link;
  /// Its parameter file's name, e.g. "tau.json": devices/<folder>/params/<file> in the sources, found
  /// by name in the parameter folder (params_location.hpp).
  std::string params_file;
  /// The board as the host sees it: joint and actuator counts and effort limits from the device's
  /// model, written into spec.descriptor with DeviceDescriptor::fromParams; rates stated twice
  /// (model and "usb" section) are checked to agree. Throws Error naming the file and field.
  void (*describe_board)(const DeviceDefinition& self, const ParamFile& file, BoardSpec& spec) = nullptr;
  /// The simulated device as its board drives it, with its own user (the "sim" joint I/O and the
  /// board emulator's device), its model loaded from the parameter file at params_path.
  std::unique_ptr<BoardPlant> (*make_plant)(const std::string& params_path) = nullptr;
  /// The same simulated device integrating in steps of step_period [s] instead of its board's
  /// sampling period, for a caller that runs a faster servo loop on the plant (the Z-width harness
  /// at 2-4 kHz); nullptr where make_plant's plant already resolves any period (its own step is
  /// finer) or has no step to change. Throws Error for a step the simulation refuses.
  std::unique_ptr<BoardPlant> (*make_plant_stepped)(const std::string& params_path, double step_period) = nullptr;
  /// The simulated device without a user of its own, for a caller that simulates the user on the end
  /// effector (BoardPlant::setUserForce: the task-space Z-width harness), integrating in steps of
  /// step_period [s] (0: its board's sampling period). nullptr where the device's user is
  /// position-driven (the exoskeleton's finger takes no force).
  std::unique_ptr<BoardPlant> (*make_userless_plant)(const std::string& params_path, double step_period) = nullptr;
  /// The viscous damping [N s/m] of the hand make_plant's user holds the end effector with: what a
  /// caller that simulates the user in its place puts on the end effector.
  double hand_damping = 0.0;
};

/// The registered devices, in registration order (validated once: names and codes unique).
const std::vector<const DeviceDefinition*>& deviceDefinitions();
/// By name; throws Error listing the registered names.
const DeviceDefinition& findDevice(const std::string& name);
/// By protocol device code; nullptr when no device has it.
const DeviceDefinition* findDevice(wire::DeviceType code);
/// "exo, tau or rhi": the registered names, for messages.
std::string deviceNameList();
/// The first registered device reproducing the paper with this id; nullptr when none does.
const DeviceDefinition* findDeviceByPaper(const std::string& paper_id);

}  // namespace uhaptics
