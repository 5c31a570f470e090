#include "device_servo_renderers.hpp"

#include <cmath>

#include "uhaptics/backends/board_catalog.hpp"
#include "uhaptics/core/fault.hpp"
#include "uhaptics/renderers/tau_wall_design.hpp"

namespace uhaptics {
namespace {

ExoServoRenderer::Renderer::Gains exoGains(const ExoFingerModel& model) {
  ExoServoRenderer::Renderer::Gains g;
  // 400 N/m on the actuator stroke: about 10 N at a quarter of the 50 mm stroke from the proxy,
  // well inside the 50 N limit over the flexion cycle, so the safety stage has nothing to do.
  g.Zq(0, 0) = 400.0;
  g.force_limit = model.forceLimit();
  return g;
}

}  // namespace

ExoServoRenderer::ExoServoRenderer(ExoFingerModel model)
    : model_(std::make_unique<const ExoFingerModel>(std::move(model))),
      renderer_(*model_, exoGains(*model_)),
      proxy_(0.5 * (model_->taskLower() + model_->taskUpper())) {}

void ExoServoRenderer::render(const DeviceSnapshot& s, const EffortRequest& r, double* efforts) noexcept {
  const ExoFingerModel::JointVector q(s.position[0], s.position[1]);
  ExoFingerModel::ActuatorVector tau;
  if (renderer_.tick(q, proxy_, tau) != Fault::kNone) ++faults_;
  efforts[0] = tau(0);
  addRequest(r, 1, efforts);
}

TauServoRenderer::TauServoRenderer(TauModel model)
    : model_(std::make_unique<const TauModel>(std::move(model))),
      wall_(*model_, designLqrWall(*model_, model_->homePose()).gains) {}

void TauServoRenderer::render(const DeviceSnapshot& s, const EffortRequest& r, double* efforts) noexcept {
  const Vec6 q = Eigen::Map<const Vec6>(s.position.data());
  const WallCommand& c = wall_.tick(q, free_space_);
  if (c.fault != Fault::kNone) ++faults_;
  for (int i = 0; i < 6; ++i) efforts[i] = c.torque(i);
  addRequest(r, 6, efforts);
}

RhiServoRenderer::RhiServoRenderer(Rhi4Model model)
    : model_(std::make_unique<const Rhi4Model>(std::move(model))),
      controller_(*model_, model_->torqueLimits(), model_->home()) {}

void RhiServoRenderer::render(const DeviceSnapshot& s, const EffortRequest& r, double* efforts) noexcept {
  const Vec<4> q = Eigen::Map<const Vec<4>>(s.position.data());
  const double t = 1e-6 * s.board_time_us;
  // Joint velocity over the board's sample clock (not the host's wake-up time).
  Vec<4> qd;
  rate_.update(s.position.data(), 4, s.sample_time_us[0], qd.data());
  const Vec2 force(0.0, 2.0 * std::sin(2.0 * M_PI * 0.5 * t));  // N, along paper 003's palpation axis u
  Vec<4> tau;
  if (controller_.tick(t, q, qd, force, tau) != Fault::kNone) ++faults_;
  for (int i = 0; i < 4; ++i) efforts[i] = tau(i);
  addRequest(r, 4, efforts);
}

std::unique_ptr<DeviceServoRenderer> makeDeviceRenderer(wire::DeviceType type, const std::string& params_dir) {
  const std::string path = params_dir + "/" + paramsFileName(type);  // throws for the test plant
  switch (type) {
    case wire::DeviceType::kExoFinger: return std::make_unique<ExoServoRenderer>(ExoFingerModel::load(path));
    case wire::DeviceType::kTau: return std::make_unique<TauServoRenderer>(TauModel::load(path));
    case wire::DeviceType::kRhiPlanar: return std::make_unique<RhiServoRenderer>(Rhi4Model::fromFile(path, "rhi4"));
    case wire::DeviceType::kTestPlant: break;
  }
  throw Error("makeDeviceRenderer: no renderer for the test plant");
}

}  // namespace uhaptics
