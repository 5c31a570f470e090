// The TAU's renderer in the servo thread: the LQR wall (paper 001) in free space, i.e. gravity
// compensation with the observer running.
#include "device_servo_renderers.hpp"
#include "uhaptics/models/tau_model.hpp"
#include "uhaptics/renderers/lqr_wall_renderer.hpp"
#include "uhaptics/renderers/tau_wall_design.hpp"

namespace uhaptics::devices::tau {
namespace {

class TauServoRenderer final : public DeviceServoRenderer {
 public:
  // It runs in a board's servo thread, whose commands act a period after their reading.
  static constexpr int kDelay = ServoLoop::kCommandDelayPeriods;

  explicit TauServoRenderer(TauModel model)
      : model_(std::make_unique<const TauModel>(std::move(model))),
        wall_(*model_, designLqrWall(*model_, model_->homePose(), {}, observerNoiseForDelay(kDelay), kDelay).gains) {}

  void render(const DeviceSnapshot& s, const EffortRequest& r, double* efforts) noexcept override {
    const Vec6 q = Eigen::Map<const Vec6>(s.position.data());
    const WallCommand& c = wall_.tick(q, free_space_);
    if (c.fault != Fault::kNone) ++faults_;
    for (int i = 0; i < 6; ++i) efforts[i] = c.torque(i);
    addRequest(r, 6, efforts);
  }

 private:
  std::unique_ptr<const TauModel> model_;
  LqrWallRenderer wall_;
  SurfaceContact free_space_;  // inactive: no wall, the renderer compensates gravity
};

}  // namespace

std::unique_ptr<DeviceServoRenderer> makeServoRenderer(const std::string& params_path) {
  return std::make_unique<TauServoRenderer>(TauModel::load(params_path));
}

}  // namespace uhaptics::devices::tau
