#pragma once
// uhaptics::ExoFingerPolicy: how one finger module of the underactuated hand exoskeleton (paper 000)
// renders a scene, on every backend and for every caller (device_policy.hpp). One actuated joint
// (actuator length l_x), one sensed-only joint (rocker q_B); the virtual finger has two joints
// (MCP, PIP).
//
// Device frame: the fingertip, in the finger's flexion plane mapped onto the device frame's y-z
// plane (finger pointing along +y, palm facing -z; x is never sensed nor actuated), origin at the
// centre of the fingertip's reachable region.
//
// Rendering (paper 000's subspace proxy): the Cartesian force F a scene sends is the proxy spring's
// pull, so it is read back as a proxy displacement through the coupling stiffness: finger-joint
// torque J_tip^T F, task proxy x_p = f(q) + Z_x^-1 J_tip^T F; the nonlinear subspace proxy
// q* = argmin |x_p - f(q*)| then gives the actuator force Z_q S (q* - q). Only what the actuated
// subspace can display is displayed, so the device stays passive (eq. 9) where projecting F directly
// (the standard method, Method::kStandard) is not. The paper's other baseline, null-space force
// optimization (Method::kNullSpace, eq. 3-5), renders the same pull for comparison.
//
// Figures (FigureRecorder):
//   proxy_solves           periods in which the subspace proxy was solved (free space skips it: the
//                          proxy is then the probe)
//   proxy_contact_ticks    of those, periods that rendered a contact: no fault, and the scene's pull
//                          (Cartesian force and multi-point joint torque, as one fingertip force)
//                          above kContactThreshold
//   max_proxy_distance_mm  largest fingertip distance between the probe f(q) and the proxy target
//                          the solve used, x_p [mm]
//   max_actuator_force_N   largest |actuator command| sent [N]
//   active_impedance_ticks contact periods in which the displayed impedance d tau / d q of the method
//                          running (its theoretical form at the finger's configuration: eq. 9,
//                          -S^T Z_q S, for the subspace proxy; eq. 2, -S^T S J^T Z_x J, for the
//                          standard method; eq. 5 for null-space optimization) has a positive eigenvalue in its symmetric part: the
//                          device can return more energy than the proxy spring stored (paper 000,
//                          Fig. 4). Zero with the subspace proxy; the standard method couples the
//                          actuator to the sensed-only joint and goes active in parts of the range.
#include <memory>

#include "uhaptics/models/exo_finger_model.hpp"
#include "uhaptics/renderers/device_policy.hpp"
#include "uhaptics/renderers/underactuated_renderers.hpp"

namespace uhaptics {

class ExoFingerPolicy final : public DevicePolicy {
 public:
  using Model = ExoFingerModel;
  /// The CHAI3D option "method": 0, 1, 2 in this order.
  enum class Method { kSubspaceProxy, kStandard, kNullSpace };
  /// [N] a fingertip pull above this is a contact (the session statistics' contact threshold).
  static constexpr double kContactThreshold = 0.05;

  struct Options {
    double coupling_stiffness = 1.0;  // Z_x [N m/rad], > 0
    Method method = Method::kSubspaceProxy;
    double servo_period = 1.0 / 500.0;  // [s] between readings (the fingertip velocity's difference)
  };

  /// Surveys the finger's working range (workspace, actuator lever). Throws uhaptics::Error when no
  /// configuration of it assembles or an option is out of range.
  ExoFingerPolicy(Model model, const Options& options, FigureRecorder& figures);

  std::string name() const override;
  void reset(int command_delay) override;
  void sense(const SensedJoints& reading, SensedState& state) noexcept override;
  Fault render(const SceneInput& input, double* efforts) noexcept override;
  void endSession() noexcept override;
  /// The referee's port is the actuator (the plant's truth: l_x and its force, x = l_x): the scene's
  /// pull there as the standard method maps it, S J^T Z_x (x_p - x), from the last render (zero when
  /// the scene asks nothing).
  Vec3 sceneForceAtUserPort(const Vec3& force) const noexcept override {
    return force.isZero(0.0) && finger_torque_.isZero(0.0) ? Vec3::Zero() : Vec3(scene_actuator_force_, 0.0, 0.0);
  }

  /// Set-up, between sessions (an experiment's, e.g. paper 000's Fig. 4): the method the next
  /// render() uses, and the coupling stiffness Z_x [N m/rad] with Z_q following it. A CHAI3D
  /// device's specification keeps the constructor's. Throws Error for a stiffness not finite and > 0.
  void setMethod(Method method) noexcept { method_ = method; }
  Method method() const noexcept { return method_; }
  void setCouplingStiffness(double stiffness);
  double couplingStiffness() const noexcept { return coupling_stiffness_; }
  /// Z_q [N/m]: the coupling stiffness seen at l_x, Z_x avg(|d x / d l_x|^2) over the working range.
  double actuatorStiffness() const noexcept { return actuator_stiffness_; }

  const Model& model() const noexcept { return *model_; }
  /// The finger as last sensed (joints, finger angles x, phalanx points).
  const ExoFingerData& data() const noexcept { return data_; }
  /// The actuator force of the latest period [N].
  double actuatorForce() const noexcept { return actuator_(0); }
  /// A hand-frame point (model geometry) in the device frame [m].
  Vec3 handToDevice(const Vec2& hand_point) const noexcept { return planarToDevice(hand_point - centre_); }
  /// The device frame's origin in the hand frame [m].
  const Vec2& centre() const noexcept { return centre_; }
  /// From the survey: the inscribed radius of the fingertip's reachable box [m], the fingertip force
  /// the actuator shows on average over the range [N], and the coupling stiffness seen at the
  /// fingertip [N/m].
  double workspaceRadius() const noexcept { return workspace_radius_; }
  double fingertipForce() const noexcept { return fingertip_force_; }
  double fingertipStiffness() const noexcept { return fingertip_stiffness_; }
  /// Multi-point tools: a virtual-finger joint torque (MCP, PIP) [N m] from contacts on several
  /// phalanges, added to the one read from the Cartesian force and held until replaced; rendered
  /// through the subspace proxy like that one. Non-finite input counts as zero.
  void setFingerJointTorque(const Vec2& torque) noexcept { finger_torque_ = torque.allFinite() ? torque : Vec2::Zero(); }
  const Vec2& fingerJointTorque() const noexcept { return finger_torque_; }

 private:
  Vec2 fingertip(const Model::TaskVector& x) const noexcept;
  /// d fingertip / d x (hand frame), in closed form.
  Mat2 fingertipJacobian(const Model::TaskVector& x) const noexcept;

  std::unique_ptr<const Model> model_;  // the renderers keep references to it
  FigureRecorder& figures_;
  const Options options_;
  std::unique_ptr<NonlinearSubspaceRenderer<Model>> subspace_;
  std::unique_ptr<StandardRenderer<Model>> standard_;
  std::unique_ptr<NullSpaceRenderer<Model>> nullspace_;
  Method method_;
  double coupling_stiffness_ = 0.0, actuator_stiffness_ = 0.0;
  double lever_sq_ = 0.0, tip_lever_sq_ = 0.0;  // avg |d x / d l_x|^2 and avg |J_tip|_F^2 / 2 over the range
  ExoFingerData data_{*model_};
  Vec2 centre_ = Vec2::Zero();  // fingertip workspace centre, hand frame
  double workspace_radius_ = 0.0, fingertip_force_ = 0.0, fingertip_stiffness_ = 0.0;
  Vec3 last_position_ = Vec3::Zero();
  Model::ActuatorVector actuator_ = Model::ActuatorVector::Zero();
  double scene_actuator_force_ = 0.0;  // the scene's pull at the actuator, S J^T Z_x (x_p - x) [N]
  Vec2 finger_torque_ = Vec2::Zero();  // setFingerJointTorque()
  int fig_contact_ticks_, fig_proxy_distance_, fig_actuator_force_, fig_solves_, fig_active_impedance_;
};

}  // namespace uhaptics
