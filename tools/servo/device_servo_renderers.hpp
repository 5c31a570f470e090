#pragma once
// Each device's own renderer as a ServoRenderer running in the servo thread, so the servo tool and
// the end-to-end tests run what an application runs: renderer -> safety stage -> wire protocol ->
// board (emulated: the device's simulation). Each device defines its own in its folder
// (devices/<device>/<device>_servo_renderer.cpp), e.g.
//
//   finger exoskeleton: linearized subspace proxy (paper 000), the proxy held fixed at the middle of
//                       the finger's range while the finger flexes and extends (as in Fig. 4)
//   TAU:                LQR wall (paper 001) in free space: gravity compensation, observer running
//   RHI planar:         FME null-space controller (paper 003) with a slow task force along u
//
// Each adds the graphics thread's effort request to its output (how a test pushes a command past
// the limits to see the safety stage act on it), owns its model (the renderers keep references to
// it) and never allocates or throws in render().
#include <cstdint>
#include <memory>
#include <string>

#include "uhaptics/backends/device_definition.hpp"
#include "uhaptics/backends/servo_loop.hpp"

namespace uhaptics {

/// What every device renderer shares: the request added, faults counted.
class DeviceServoRenderer : public ServoRenderer {
 public:
  /// Renderer faults so far (written by the servo thread: read it after stop()).
  std::uint64_t faults() const noexcept { return faults_; }

 protected:
  void addRequest(const EffortRequest& request, int n, double* efforts) noexcept {
    for (int i = 0; i < n && i < request.count; ++i) efforts[i] += request.effort[i];
  }
  std::uint64_t faults_ = 0;
};

/// The device's renderer on the model in <params_dir>/<its parameter file>; throws Error for a
/// malformed file.
std::unique_ptr<DeviceServoRenderer> makeDeviceRenderer(const DeviceDefinition& device, const std::string& params_dir);

}  // namespace uhaptics
