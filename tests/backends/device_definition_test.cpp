// The device registry: every registered definition is complete and consistent with its parameter
// file, and a device is found by name and by protocol code.
#include <catch2/catch.hpp>

#include <array>
#include <cmath>
#include <limits>
#include <set>

#include "uhaptics/backends/board_catalog.hpp"
#include "uhaptics/backends/device_definition.hpp"
#include "uhaptics/core/fault.hpp"

using namespace uhaptics;

TEST_CASE("every registered device has a unique name and wire code and a board and plant from its file",
          "[backends][devices]") {
  const auto& all = deviceDefinitions();
  REQUIRE(all.size() >= 3);  // exo, tau, rhi at least
  std::set<std::string> names;
  std::set<int> codes;
  for (const DeviceDefinition* d : all) {
    INFO(d->name);
    CHECK(names.insert(d->name).second);
    CHECK(codes.insert(d->wire_code).second);
    CHECK(d->wire_code >= 1);
    CHECK(d->wire_code <= wire::kMaxDeviceCode);
    CHECK_FALSE(d->summary.empty());
    // The paper it reproduces: the report heads that paper's rows with this title.
    CHECK_FALSE(d->paper.id.empty());
    CHECK_FALSE(d->paper.title.empty());
    REQUIRE(findDeviceByPaper(d->paper.id) != nullptr);
    CHECK(findDeviceByPaper(d->paper.id)->paper.title == d->paper.title);  // one title per paper id
    CHECK(&findDevice(d->name) == d);
    CHECK(findDevice(wire::DeviceType{d->wire_code}) == d);
    // The board the host expects: the definition's code and title, counts and limits from the model.
    const BoardSpec spec = boardSpec(*d, UHAPTICS_PARAMS_DIR);
    CHECK(spec.descriptor.type == wire::DeviceType{d->wire_code});
    CHECK(spec.descriptor.name == d->title);
    // The plant its sim and emulated backends drive has the board's channels and reads finite joints.
    const auto plant = d->make_plant(spec.params_path);
    REQUIRE(plant != nullptr);
    CHECK(plant->jointCount() == spec.descriptor.joints);
    CHECK(plant->actuatorCount() == spec.descriptor.actuators);
    std::array<double, wire::kMaxChannels> q{};
    q.fill(std::numeric_limits<double>::quiet_NaN());
    plant->readJoints(q.data());
    for (int i = 0; i < spec.descriptor.joints; ++i) CHECK(std::isfinite(q[static_cast<std::size_t>(i)]));
  }
}

TEST_CASE("an unknown device name is refused with the registered names", "[backends][devices]") {
  CHECK_THROWS_WITH(findDevice("phantom"), Catch::Contains("unknown device 'phantom'") && Catch::Contains("tau"));
  CHECK(findDevice(wire::DeviceType::kTestPlant) == nullptr);
  CHECK(findDevice(wire::DeviceType{wire::kMaxDeviceCode}) == nullptr);
  CHECK(findDeviceByPaper("999") == nullptr);
}
