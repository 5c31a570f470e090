#pragma once
// Each device's own renderer as a ServoRenderer running in the servo thread, so the servo tool and
// the end-to-end tests run what an application runs: renderer -> safety stage -> wire protocol ->
// board (emulated: the device's simulation). Each adds the graphics thread's effort request to its
// output (how a test pushes a command past the limits to see the safety stage act on it).
//
//   finger exoskeleton: linearized subspace proxy (paper 000), the proxy held fixed at the middle of
//                       the finger's range while the finger flexes and extends (as in Fig. 4)
//   TAU:                LQR wall (paper 001) in free space: gravity compensation, observer running
//   RHI planar:         FME null-space controller (paper 003) with a slow task force along u
//
// Each owns its model (the renderers keep references to it). render() never allocates or throws.
#include <cstdint>
#include <memory>
#include <string>

#include "uhaptics/backends/joint_io.hpp"
#include "uhaptics/backends/servo_loop.hpp"
#include "uhaptics/models/exo_finger_model.hpp"
#include "uhaptics/models/planar_linkage_model.hpp"
#include "uhaptics/models/tau_model.hpp"
#include "uhaptics/renderers/fme_null_space_controller.hpp"
#include "uhaptics/renderers/lqr_wall_renderer.hpp"
#include "uhaptics/renderers/underactuated_renderers.hpp"

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

class ExoServoRenderer final : public DeviceServoRenderer {
 public:
  using Renderer = LinearizedSubspaceRenderer<ExoFingerModel>;
  explicit ExoServoRenderer(ExoFingerModel model);
  void render(const DeviceSnapshot& s, const EffortRequest& r, double* efforts) noexcept override;

 private:
  std::unique_ptr<const ExoFingerModel> model_;
  Renderer renderer_;
  ExoFingerModel::TaskVector proxy_;
};

class TauServoRenderer final : public DeviceServoRenderer {
 public:
  explicit TauServoRenderer(TauModel model);
  void render(const DeviceSnapshot& s, const EffortRequest& r, double* efforts) noexcept override;

 private:
  std::unique_ptr<const TauModel> model_;
  LqrWallRenderer wall_;
  SurfaceContact free_space_;  // inactive: no wall, the renderer compensates gravity
};

class RhiServoRenderer final : public DeviceServoRenderer {
 public:
  using Controller = FmeNullSpaceController<Rhi4Model>;
  explicit RhiServoRenderer(Rhi4Model model);
  void render(const DeviceSnapshot& s, const EffortRequest& r, double* efforts) noexcept override;

 private:
  std::unique_ptr<const Rhi4Model> model_;
  Controller controller_;
  JointRateEstimator rate_;
};

/// The device's renderer on the model in <params_dir>/<device file>; throws Error for kTestPlant or
/// a malformed file.
std::unique_ptr<DeviceServoRenderer> makeDeviceRenderer(wire::DeviceType type, const std::string& params_dir);

}  // namespace uhaptics
