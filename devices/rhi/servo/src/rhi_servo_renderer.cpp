// The RHI's renderer in the servo thread: the FME null-space controller (paper 003) with a slow
// task force along paper 003's palpation axis u.
#include <cmath>

#include "device_servo_renderers.hpp"
#include "uhaptics/backends/joint_io.hpp"
#include "uhaptics/models/planar_linkage_model.hpp"
#include "uhaptics/renderers/fme_null_space_controller.hpp"

namespace uhaptics::devices::rhi {
namespace {

class RhiServoRenderer final : public DeviceServoRenderer {
 public:
  using Controller = FmeNullSpaceController<Rhi4Model>;
  explicit RhiServoRenderer(Rhi4Model model)
      : model_(std::make_unique<const Rhi4Model>(std::move(model))),
        controller_(*model_, model_->effortLimits(), model_->homeJoints()) {}

  void render(const DeviceSnapshot& s, const EffortRequest& r, double* efforts) noexcept override {
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

 private:
  std::unique_ptr<const Rhi4Model> model_;
  Controller controller_;
  JointRateEstimator rate_;
};

}  // namespace

std::unique_ptr<DeviceServoRenderer> makeServoRenderer(const std::string& params_path) {
  return std::make_unique<RhiServoRenderer>(Rhi4Model::load(params_path, "rhi4"));
}

}  // namespace uhaptics::devices::rhi
