#include "uhaptics/renderers/planar_fme_policy.hpp"

namespace uhaptics {

template <int N>
PlanarFmePolicy<N>::PlanarFmePolicy(Model model, const typename Controller::Options& options, FigureRecorder& figures)
    : model_(std::make_unique<const Model>(std::move(model))), figures_(figures) {
  controller_ = std::make_unique<Controller>(*model_, model_->effortLimits(), model_->homeJoints(), options);
  model_->forward(model_->homeJoints(), centre_);
  fig_free_to_stiff_ = figures_.declareFigure("free_to_stiff", FigureKind::kCount);
  fig_stiff_to_free_ = figures_.declareFigure("stiff_to_free", FigureKind::kCount);
  fig_stiff_ticks_ = figures_.declareFigure("stiff_ticks", FigureKind::kCount);
  fig_force_scale_reduction_ = figures_.declareFigure("max_force_scale_reduction", FigureKind::kMaximum);
  fig_null_space_torque_ = figures_.declareFigure("max_null_space_torque_Nm", FigureKind::kMaximum);
  fig_tank_drawn_ = figures_.declareFigure("null_space_tank_drawn_mJ", FigureKind::kMaximum);
}

template <int N>
void PlanarFmePolicy<N>::reset(int) {
  controller_->reset();
  stiff_target_ = controller_->status().omega_target == 0.0;
  tau_.setZero();
}

template <int N>
void PlanarFmePolicy<N>::sense(const SensedJoints& reading, SensedState& state) noexcept {
  q_ = Eigen::Map<const typename Model::JointVector>(reading.positions);
  qd_ = Eigen::Map<const typename Model::JointVector>(reading.rates);
  Vec2 x;
  typename Model::Jacobian J;
  model_->forwardAndJacobian(q_, x, J);
  state.position = planarToDevice(x - centre_);
  state.linear_velocity = planarToDevice(J * qd_);
  state.joints = q_;
}

template <int N>
Fault PlanarFmePolicy<N>::render(const SceneInput& input, double* efforts) noexcept {
  // A planar device: only the in-plane force is rendered (no torque, x not actuated).
  const Fault fault = controller_->tick(input.time, q_, qd_, deviceToPlanar(input.force), tau_);
  recordFigures(controller_->status());
  Eigen::Map<typename Model::JointVector> out(efforts);
  out = tau_;
  return fault;
}

template <int N>
void PlanarFmePolicy<N>::recordFigures(const typename Controller::Status& status) noexcept {
  // A switch is where the desired ellipsoid starts moving towards the other one (the observer's
  // hysteresis decision, or a change of mode); a reversal mid-blend counts as a switch back.
  const bool stiff_target = status.omega_target == 0.0;
  if (stiff_target && !stiff_target_) figures_.count(fig_free_to_stiff_);
  if (!stiff_target && stiff_target_) figures_.count(fig_stiff_to_free_);
  stiff_target_ = stiff_target;
  if (status.omega < 1.0) figures_.count(fig_stiff_ticks_);  // any share of the stiff ellipsoid, blends included
  figures_.observeMaximum(fig_force_scale_reduction_, 1.0 - status.alpha);
  figures_.observeMaximum(fig_null_space_torque_, status.tau_null.norm());
  const double capacity = controller_->options().null_space_tank_capacity;
  if (std::isfinite(capacity)) figures_.observeMaximum(fig_tank_drawn_, 1e3 * (capacity - status.null_space_tank));
}

template class PlanarFmePolicy<3>;
template class PlanarFmePolicy<4>;

}  // namespace uhaptics
