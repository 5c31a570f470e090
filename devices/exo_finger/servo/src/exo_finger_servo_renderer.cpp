// The finger exoskeleton's renderer in the servo thread: the linearized subspace proxy (paper 000),
// the proxy held fixed at the middle of the finger's range while the finger flexes and extends.
#include "device_servo_renderers.hpp"
#include "uhaptics/models/exo_finger_model.hpp"
#include "uhaptics/renderers/underactuated_renderers.hpp"

namespace uhaptics::devices::exo_finger {
namespace {

class ExoServoRenderer final : public DeviceServoRenderer {
 public:
  using Renderer = LinearizedSubspaceRenderer<ExoFingerModel>;
  explicit ExoServoRenderer(ExoFingerModel model)
      : model_(std::make_unique<const ExoFingerModel>(std::move(model))),
        renderer_(*model_, gains(*model_)),
        proxy_(0.5 * (model_->taskLower() + model_->taskUpper())) {}

  void render(const DeviceSnapshot& s, const EffortRequest& r, double* efforts) noexcept override {
    const ExoFingerModel::JointVector q(s.position[0], s.position[1]);
    ExoFingerModel::ActuatorVector tau;
    if (renderer_.tick(q, proxy_, tau) != Fault::kNone) ++faults_;
    efforts[0] = tau(0);
    addRequest(r, 1, efforts);
  }

 private:
  static Renderer::Gains gains(const ExoFingerModel& model) {
    Renderer::Gains g;
    // 400 N/m on the actuator stroke: about 10 N at a quarter of the 50 mm stroke from the proxy,
    // well inside the 50 N limit over the flexion cycle, so the safety stage has nothing to do.
    g.Zq(0, 0) = 400.0;
    g.force_limit = model.effortLimits();
    return g;
  }
  std::unique_ptr<const ExoFingerModel> model_;
  Renderer renderer_;
  ExoFingerModel::TaskVector proxy_;
};

}  // namespace

std::unique_ptr<DeviceServoRenderer> makeServoRenderer(const std::string& params_path) {
  return std::make_unique<ExoServoRenderer>(ExoFingerModel::load(params_path));
}

}  // namespace uhaptics::devices::exo_finger
