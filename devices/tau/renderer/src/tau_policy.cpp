#include "uhaptics/renderers/tau_policy.hpp"

#include <cmath>

#include "uhaptics/core/limits.hpp"
#include "uhaptics/models/tau_kinematics.hpp"
#include "uhaptics/renderers/tau_wall_design.hpp"

namespace uhaptics {

TauPolicy::TauPolicy(TauModel model, const Options& options, FigureRecorder& figures)
    : model_(std::make_unique<const TauModel>(std::move(model))),
      figures_(figures),
      wall_mode_(static_cast<int>(options.wall_mode)),
      rated_spring_(options.rated_spring),
      classifier_([&] {
        TauContactClassifier::Options o = options.classifier;
        o.servo_period = model_->servoPeriod();
        o.nominal_stiffness = kSpringWallStiffness;
        return o;
      }()) {
  centre_ = model_->homePose().head<3>();
  data_ = std::make_unique<TauData>(*model_);
  // LQR gains at the workspace centre (paper 001 linearizes at one operating point), for the
  // undelayed plant until reset() is given the caller's command delay.
  lqr_ = makeWall(0);
  for (Vec6& sent : sent_) sent.setZero();

  using Kind = FigureKind;
  fig_engagements_ = figures_.declareFigure("lqr_engagements", Kind::kCount);
  fig_releases_ = figures_.declareFigure("lqr_releases", Kind::kCount);
  fig_held_ticks_ = figures_.declareFigure("lqr_held_ticks", Kind::kCount);
  fig_entry_depth_ = figures_.declareFigure("max_entry_depth_mm", Kind::kMaximum);
  fig_max_penetration_ = figures_.declareFigure("max_penetration_mm", Kind::kMaximum);
  fig_saturated_ticks_ = figures_.declareFigure("lqr_saturated_ticks", Kind::kCount);
  fig_spring_ticks_ = figures_.declareFigure("spring_contact_ticks", Kind::kCount);
  fig_soft_contacts_ = figures_.declareFigure("soft_surface_contacts", Kind::kCount);
  fig_soft_stiffness_ = figures_.declareFigure("soft_stiffness_max_N_per_m", Kind::kMaximum);
  fig_overloads_ = figures_.declareFigure("lqr_overloads", Kind::kCount);
}

std::string TauPolicy::name() const {
  if (lqr_engaged_.load()) return "LQR wall";
  return wallMode() == WallMode::kSpring ? "spring (J^T F)" : "spring (J^T F), LQR wall on stiff contact";
}

std::unique_ptr<LqrWallRenderer> TauPolicy::makeWall(int delay) const {
  CommandDelayDesign delay_model;
  delay_model.samples = delay;
  delay_model.random = design_.random_delay && delay > 0;
  delay_model.rate_weight = delay_model.random ? design_.delay_rate_weight : 0.0;
  const ObserverNoise noise = design_.custom_observer_noise ? design_.observer_noise : observerNoiseForDelay(delay);
  const LqrWallDesign design = designLqrWall(*model_, model_->homePose(), design_.weights, noise, delay_model);
  return std::make_unique<LqrWallRenderer>(*model_, design.gains, design_.renderer);
}

void TauPolicy::setWallDesign(const WallDesign& design) {
  design_ = design;
  design_changed_ = true;
}

void TauPolicy::reset(int command_delay) {
  if (command_delay != wall_delay_ || design_changed_) {
    lqr_ = makeWall(command_delay);
    wall_delay_ = command_delay;
    design_changed_ = false;
  }
  applied_age_ = -1;
  lqr_->reset();
  for (Vec6& sent : sent_) sent.setZero();
  data_->pose = model_->homePose();  // forward kinematics' first guess
  classifier_.reset();
  classifier_.setSpringLimit(rated_spring_[command_delay > 0 ? 1 : 0]);
  lqr_engaged_ = false;
  tau_.setZero();
  own_.setZero();
}

void TauPolicy::sense(const SensedJoints& reading, SensedState& state) noexcept {
  const Eigen::Map<const Vec6> q(reading.positions);
  // The encoders' counts repeat while the tool is held or slow: their pose is the one solved.
  if (reading.first || sense_fault_ != Fault::kNone || q != q_) {
    q_ = q;
    sense_fault_ = model_->forward(q_, *data_);  // the wall and the scene work from the encoders
    if (sense_fault_ == Fault::kNone) rotation_ = PoseRotation(data_->pose).R;
  }
  if (sense_fault_ != Fault::kNone) return;  // the last assembled state stays
  // Rates through the Jacobian. The angular rates are pose-angle rates; within the TAU's +-10 deg
  // they are the angular velocity to within 2 %.
  const Vec6& pose = data_->pose;
  const Vec6 rates = data_->J * Eigen::Map<const Vec6>(reading.rates);
  state.position = pose.head<3>() - centre_;
  state.rotation = rotation_;
  state.linear_velocity = rates.head<3>();
  state.angular_velocity = rates.tail<3>();
  state.joints = q_;
}

void TauPolicy::checkFirstReading() const {
  if (sense_fault_ != Fault::kNone) {
    throw Error("TAU: the first joint reading does not assemble (forward kinematics fails)");
  }
}

void TauPolicy::readingLost() noexcept {
  tau_.setZero();
  own_.setZero();
  for (Vec6& sent : sent_) sent.setZero();  // the device is held at zero meanwhile
  lqr_engaged_ = false;
  classifier_.holdLost();
}

void TauPolicy::commandApplied(int periods_ago) noexcept {
  applied_age_ = periods_ago >= 0 && periods_ago <= kMaxCommandDelay ? periods_ago : -1;
}

void TauPolicy::endSession() noexcept {
  tau_.setZero();
  own_.setZero();
  lqr_engaged_ = false;
  classifier_.endContact();  // no release counted: the session ends
  explicit_.active = false;
}

bool TauPolicy::contactSurface(Vec3& point, Vec3& normal) const noexcept {
  const SurfaceContact& surface = classifier_.surface();
  if (!surface.active) return false;
  point = surface.point - centre_;  // model frame -> device frame
  normal = surface.normal;
  return true;
}

void TauPolicy::setContactSurface(bool active, const Vec3& point, const Vec3& normal) noexcept {
  const double length = normal.norm();
  explicit_surface_ = true;
  explicit_.active = active && point.allFinite() && std::isfinite(length) && length > 0.0;
  if (explicit_.active) {
    explicit_.point = point + centre_;  // device frame -> model frame
    explicit_.normal = normal / length;
  }
}

void TauPolicy::clearContactSurface() noexcept {
  explicit_surface_ = false;
  explicit_.active = false;
  if (classifier_.endContact()) figures_.count(fig_releases_);
}

void TauPolicy::recordFigures(const TauContactClassifier::Events& events, const Vec3& force) noexcept {
  if (events.engaged) figures_.count(fig_engagements_);
  if (events.released) figures_.count(fig_releases_);
  if (events.overload) figures_.count(fig_overloads_);
  if (events.soft_contact) {
    figures_.count(fig_soft_contacts_);
    figures_.observeMaximum(fig_soft_stiffness_, events.soft_stiffness);
  }
  if (events.held) {
    figures_.count(fig_held_ticks_);
    if (events.hold_started) figures_.observeMaximum(fig_entry_depth_, events.entry_depth * 1e3);
    figures_.observeMaximum(fig_max_penetration_, events.penetration * 1e3);
    if (events.saturated) figures_.count(fig_saturated_ticks_);
  } else if (force.norm() >= 0.5 * classifier_.options().contact_force) {
    figures_.count(fig_spring_ticks_);
  }
}

void TauPolicy::ownEfforts(double* efforts) const noexcept { Eigen::Map<Vec6>(efforts) += own_; }

bool TauPolicy::actuatedInertia(double* inertia) const {
  TauData data(*model_);
  data.pose = data_->pose;
  if (model_->forward(q_, data) != Fault::kNone || model_->computeDynamicsTerms(q_, Vec6::Zero(), data) != Fault::kNone ||
      !data.M.allFinite())
    return false;
  Eigen::Map<Mat6> out(inertia);
  out = data.M;
  return true;
}

Fault TauPolicy::render(const SceneInput& input, double* efforts) noexcept {
  // input.dt is the model's servo period (the classifier is built for it).
  const Vec3 reported = input.seen_position + centre_;  // model frame
  Fault fault = sense_fault_;
  if (fault == Fault::kNone) {
    if (explicit_surface_) {
      classifier_.follow(explicit_);
    } else {
      // The scene computed its force from the position reported after the previous period.
      classifier_.update(input.force, reported, wallMode());
    }
    const SurfaceContact& surface = classifier_.surface();
    // sense() solved the forward kinematics of q_ (sense_fault_ is kNone): the wall reuses them.
    // Under a random delay nothing but the board's report says which command acted: without one,
    // the wall's observer takes the delay model's expectation (nullptr).
    const Vec6* applied = applied_age_ >= 0                 ? &sent_[applied_age_]
                          : lqr_->regulator().gains().random_command_delay ? nullptr
                                                                            : &sent_[wall_delay_];
    applied_age_ = -1;
    const WallCommand& wall = lqr_->tick(q_, surface, *data_, applied);
    fault = wall.fault;
    tau_ = own_ = wall.torque;
    classifier_.wallTicked(wall);
    const TauContactClassifier::Events& events = classifier_.events();
    lqr_engaged_ = explicit_surface_ ? events.held : classifier_.state() == TauContactClassifier::State::kLqr;
    recordFigures(events, input.force);
    if (events.held) {
      if (!explicit_surface_) {
        // The scene's force across the wall's normal (a second face of a concave edge or corner,
        // friction, a mesh's facets): rendered as sent, by the spring.
        const Vec3 across = input.force - surface.normal.dot(input.force) * surface.normal;
        tau_.noalias() += data_->J.topRows<3>().transpose() * across;
        clampSymmetric(tau_, model_->effortLimits());
      }
    } else {
      Vec6 wrench;
      wrench << input.force, input.torque;
      tau_.noalias() += data_->J.transpose() * wrench;  // the scene's spring (the baseline)
      scaleIntoBox(tau_, model_->effortLimits());
    }
  }
  if (fault != Fault::kNone || !tau_.allFinite()) {
    tau_.setZero();
    own_.setZero();
    classifier_.holdLost();
    if (fault == Fault::kNone) fault = Fault::kNonFiniteResult;
  }
  for (int i = kMaxCommandDelay; i > 0; --i) sent_[i] = sent_[i - 1];
  sent_[0] = tau_;
  Eigen::Map<Vec6> out(efforts);
  out = tau_;
  return fault;
}

}  // namespace uhaptics
