#pragma once
// uhaptics::PlanarFmePolicy<N>: how a redundant planar linkage (PlanarLinkageModel<N>, N > 2: the
// RHI, paper 003's 3-DoF example arm) renders a scene with paper 003's force-manipulability
// null-space control, on every backend and for every caller (device_policy.hpp). N actuated joints
// for a 2-D task, N - 2 degrees of self-motion.
//
// Device frame: the task plane mapped onto the device frame's y-z plane (the paper's x to +y, its y,
// the palpation direction u, to -z: pressing down palpates), origin at the home configuration's
// end-effector position; x is never sensed nor actuated.
//
// Rendering: tau = J^T (alpha F) + (I - J^T J#^T) tau_S (FmeNullSpaceController): the scene's force
// is the primary task, rendered unchanged (scaled as a whole only when an actuator would saturate);
// the null space reshapes the force manipulability ellipsoid (light in free motion, strong along a
// stiff contact force) without changing the force at the tool.
//
// Figures (FigureRecorder):
//   free_to_stiff              count: switches of the desired ellipsoid towards the stiff-contact one
//                              (the observer fell below eps1, or the mode changed to stiff)
//   stiff_to_free              count: switches back towards the free-motion one (a reversal during a
//                              blend counts as a switch)
//   stiff_ticks                count: periods with any share of the stiff-contact ellipsoid in the
//                              desired one (omega < 1), both blends included
//   max_force_scale_reduction  maximum of 1 - alpha, the uniform force scaling before an actuator
//                              saturates (0: the force was never scaled)
//   max_null_space_torque_Nm   maximum Euclidean norm of the applied null-space torque [N m]
//   null_space_tank_drawn_mJ   the most the null-space torque's energy tank was drawn below its
//                              capacity [mJ] (0 without a tank)
#include <memory>

#include "uhaptics/models/planar_linkage_model.hpp"
#include "uhaptics/renderers/device_policy.hpp"
#include "uhaptics/renderers/fme_null_space_controller.hpp"

namespace uhaptics {

template <int N>
class PlanarFmePolicy final : public DevicePolicy {
 public:
  using Model = PlanarLinkageModel<N>;
  using Controller = FmeNullSpaceController<Model>;
  static constexpr const char* kName = "J^T F + FME null space";
  /// The envelope this policy puts on paper 003's controller, which has none: the null-space
  /// torque's norm bound [N m], its rise time after reset [s], and the time constant of the stiff
  /// ellipsoid's axis following the contact force's direction [s] (why: cPlanarLinkageDevice's options).
  static constexpr double kDefaultMaxNullSpaceTorque = 0.5;
  static constexpr double kDefaultNullSpaceRampTime = 0.25;
  static constexpr double kDefaultStiffDirectionTime = 0.02;
  /// Paper 003's controller options with that envelope.
  static typename Controller::Options defaultOptions() {
    typename Controller::Options o;
    o.max_null_space_torque = kDefaultMaxNullSpaceTorque;
    o.null_space_ramp_time = kDefaultNullSpaceRampTime;
    o.stiff_direction_time = kDefaultStiffDirectionTime;
    return o;
  }

  /// Throws uhaptics::Error when the controller's options are invalid or inconsistent.
  PlanarFmePolicy(Model model, const typename Controller::Options& options, FigureRecorder& figures);

  std::string name() const override { return kName; }
  /// The controller to its free-motion ellipsoid; the null-space torque ramps up from zero.
  void reset(int command_delay) override;
  void sense(const SensedJoints& reading, SensedState& state) noexcept override;
  Fault render(const SceneInput& input, double* efforts) noexcept override;
  /// The null-space torque (the FME and joint-limit control); the primary task J^T (alpha F) is the scene's.
  void ownEfforts(double* efforts) const noexcept override {
    Eigen::Map<typename Model::JointVector>(efforts) += controller_->status().tau_null;
  }
  bool actuatedInertia(double* inertia) const override {
    typename Model::MassMatrix M;
    model_->massMatrix(q_, M);
    if (!M.allFinite()) return false;
    Eigen::Map<typename Model::MassMatrix> out(inertia);
    out = M;
    return true;
  }
  Vec3 deviceToModelForce(const Vec3& force) const noexcept override { return planarForce(force); }
  Vec3 modelToDevicePoint(const Vec3& point) const noexcept override {
    return planarToDevice(point.template head<2>() - centre_);
  }
  Vec3 modelToDeviceVector(const Vec3& vector) const noexcept override {
    return planarToDevice(vector.template head<2>());
  }

  const Model& model() const noexcept { return *model_; }
  Controller& controller() noexcept { return *controller_; }
  const Controller& controller() const noexcept { return *controller_; }
  /// The latest joint reading.
  const typename Model::JointVector& joints() const noexcept { return q_; }

 private:
  void recordFigures(const typename Controller::Status& status) noexcept;

  std::unique_ptr<const Model> model_;  // the controller keeps a reference
  FigureRecorder& figures_;
  std::unique_ptr<Controller> controller_;
  Vec2 centre_ = Vec2::Zero();  // end effector at home, task frame
  typename Model::JointVector tau_ = Model::JointVector::Zero();
  typename Model::JointVector q_ = Model::JointVector::Zero();   // the latest joint reading
  typename Model::JointVector qd_ = Model::JointVector::Zero();  // its rates
  int fig_free_to_stiff_, fig_stiff_to_free_, fig_stiff_ticks_, fig_force_scale_reduction_, fig_null_space_torque_,
      fig_tank_drawn_;
  bool stiff_target_ = false;  // the last period headed for the stiff ellipsoid
};

extern template class PlanarFmePolicy<3>;
extern template class PlanarFmePolicy<4>;

}  // namespace uhaptics
