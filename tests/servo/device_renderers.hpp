#pragma once
// Each device's own renderer as a ServoRenderer, so the end-to-end tests run what an application
// runs: renderer -> safety stage -> wire protocol -> board emulator -> the device's simulation.
// Each adds the graphics thread's effort request to its output (how a test pushes a command past
// the limits to see the safety stage act on a renderer's command).
//
//   finger exoskeleton: linearized subspace proxy (paper 000), the proxy held fixed at the middle of
//                       the finger's range while the simulated finger flexes and extends (Fig. 4)
//   TAU:                LQR wall (paper 001) in free space: gravity compensation, observer running
//   RHI planar:         FME null-space controller (paper 003) with a slow task force along u
#include <cmath>

#include "uhaptics/backends/servo_loop.hpp"
#include "uhaptics/models/exo_finger_model.hpp"
#include "uhaptics/models/planar_linkage_model.hpp"
#include "uhaptics/models/tau_model.hpp"
#include "uhaptics/renderers/fme_null_space_controller.hpp"
#include "uhaptics/renderers/tau_wall.hpp"
#include "uhaptics/renderers/underactuated_renderers.hpp"

namespace uhaptics::testing {

/// What every device renderer shares: the request added, faults counted.
class DeviceServoRenderer : public ServoRenderer {
 public:
  std::uint64_t faults() const noexcept { return faults_; }

 protected:
  void addRequest(const EffortRequest& request, int n, double* efforts) noexcept {
    for (int i = 0; i < n && i < request.count; ++i) efforts[i] += request.effort[i];
  }
  std::uint64_t faults_ = 0;  // written by the servo thread, read after stop()
};

class ExoServoRenderer final : public DeviceServoRenderer {
 public:
  using Renderer = LinearizedSubspaceRenderer<ExoFingerModel>;
  explicit ExoServoRenderer(const ExoFingerModel& model)
      : renderer_(model, gains(model)), proxy_(0.5 * (model.taskLower() + model.taskUpper())) {}
  void render(const DeviceSnapshot& s, const EffortRequest& r, double* efforts) noexcept override {
    const ExoFingerModel::JointVector q(s.position[0], s.position[1]);
    ExoFingerModel::ActuatorVector tau;
    if (renderer_.tick(q, proxy_, tau) != Fault::kNone) ++faults_;
    efforts[0] = tau(0);
    addRequest(r, 1, efforts);
  }
  const Renderer& renderer() const noexcept { return renderer_; }

 private:
  static Renderer::Gains gains(const ExoFingerModel& model) {
    Renderer::Gains g;
    // 400 N/m on the actuator stroke: about 10 N at a quarter of the 50 mm stroke from the proxy,
    // well inside the 50 N limit over the flexion cycle, so the safety stage has nothing to do.
    g.Zq(0, 0) = 400.0;
    g.force_limit = model.forceLimit();
    return g;
  }
  Renderer renderer_;
  ExoFingerModel::TaskVector proxy_;
};

class TauServoRenderer final : public DeviceServoRenderer {
 public:
  explicit TauServoRenderer(const TauModel& model) : wall_(model, designLqrWall(model, model.homePose())) {}
  void render(const DeviceSnapshot& s, const EffortRequest& r, double* efforts) noexcept override {
    const Vec6 q = Eigen::Map<const Vec6>(s.position.data());
    const WallCommand& c = wall_.tick(q, free_space_);
    if (c.fault != Fault::kNone) ++faults_;
    for (int i = 0; i < 6; ++i) efforts[i] = c.torque(i);
    addRequest(r, 6, efforts);
  }

 private:
  LqrWallRenderer wall_;
  SurfaceContact free_space_;  // inactive: no wall, the renderer compensates gravity
};

class RhiServoRenderer final : public DeviceServoRenderer {
 public:
  using Controller = FmeNullSpaceController<Rhi4Model>;
  explicit RhiServoRenderer(const Rhi4Model& model) : controller_(model, model.torqueLimits(), model.home()) {}
  void render(const DeviceSnapshot& s, const EffortRequest& r, double* efforts) noexcept override {
    const Vec<4> q = Eigen::Map<const Vec<4>>(s.position.data());
    const double t = 1e-6 * s.board_time_us;
    // Joint velocity from consecutive samples and their board timestamps (the board's clock, not
    // the host's wake-up time).
    const double dt = 1e-6 * static_cast<double>(s.sample_time_us[0] - previous_sample_us_);
    Vec<4> qd = Vec<4>::Zero();
    if (have_previous_ && dt > 0.0) qd = (q - previous_q_) / dt;
    previous_q_ = q;
    previous_sample_us_ = s.sample_time_us[0];
    have_previous_ = true;
    const Vec2 force(0.0, 2.0 * std::sin(2.0 * M_PI * 0.5 * t));  // N, along paper 003's palpation axis u
    Vec<4> tau;
    if (controller_.tick(t, q, qd, force, tau) != Fault::kNone) ++faults_;
    for (int i = 0; i < 4; ++i) efforts[i] = tau(i);
    addRequest(r, 4, efforts);
  }

 private:
  Controller controller_;
  Vec<4> previous_q_ = Vec<4>::Zero();
  std::uint32_t previous_sample_us_ = 0;
  bool have_previous_ = false;
};

}  // namespace uhaptics::testing
