#pragma once
// The servo-thread renderer of every planar-linkage device: paper 003's FME null-space controller
// with a slow task force along the palpation axis u (the paper's y), 2 N at 0.5 Hz.
#include <cmath>
#include <memory>

#include "device_servo_renderers.hpp"
#include "uhaptics/backends/joint_io.hpp"
#include "uhaptics/models/planar_linkage_model.hpp"
#include "uhaptics/renderers/fme_null_space_controller.hpp"

namespace uhaptics {

template <int N>
class PlanarFmeServoRenderer final : public DeviceServoRenderer {
 public:
  using Model = PlanarLinkageModel<N>;
  using Controller = FmeNullSpaceController<Model>;
  explicit PlanarFmeServoRenderer(Model model)
      : model_(std::make_unique<const Model>(std::move(model))),
        controller_(*model_, model_->effortLimits(), model_->homeJoints()) {}

  void render(const DeviceSnapshot& s, const EffortRequest& r, double* efforts) noexcept override {
    const Vec<N> q = Eigen::Map<const Vec<N>>(s.position.data());
    const double t = 1e-6 * s.board_time_us;
    // Joint velocity over the board's sample clock (not the host's wake-up time).
    Vec<N> qd;
    rate_.update(s.position.data(), N, s.sample_time_us[0], qd.data());
    const Vec2 force(0.0, 2.0 * std::sin(2.0 * M_PI * 0.5 * t));  // N, along paper 003's palpation axis u
    Vec<N> tau;
    if (controller_.tick(t, q, qd, force, tau) != Fault::kNone) ++faults_;
    for (int i = 0; i < N; ++i) efforts[i] = tau(i);
    addRequest(r, N, efforts);
  }

 private:
  std::unique_ptr<const Model> model_;
  Controller controller_;
  JointRateEstimator rate_;
};

}  // namespace uhaptics
