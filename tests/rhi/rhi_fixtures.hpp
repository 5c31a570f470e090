#pragma once
// Shared by the RHI test files: the parameter file's model (loaded once, tests/support) and
// uniformly random joint angles over a full turn (deliberately beyond the joint limits: the
// properties under test hold for any configuration).
#include <cmath>
#include <random>

#include "device_models.hpp"
#include "device_servo_renderers.hpp"
#include "uhaptics/backends/board_catalog.hpp"
#include "uhaptics/experiments/rhi_experiments.hpp"

namespace uhaptics::rhi_test {

inline const Rhi4Model& rhi4() { return test::rhi4Model(); }

/// The RHI as the product runs it: the devices' policy factory on the shipped parameter file.
inline const experiments::DeviceProduct& rhi4Product() {
  static const DeviceDefinition& device = findDevice("rhi");
  static const experiments::DeviceProduct product{[] { return makeDevicePolicy(device, test::paramsDir()); },
                                                  boardSpec(device, test::paramsDir())};
  return product;
}

inline Vec<4> randomConfiguration(std::mt19937& rng) {
  std::uniform_real_distribution<double> angle(-M_PI, M_PI);
  return Vec<4>(angle(rng), angle(rng), angle(rng), angle(rng));
}

}  // namespace uhaptics::rhi_test
