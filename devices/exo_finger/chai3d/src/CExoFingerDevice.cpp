#include "uhaptics/chai3d/CExoFingerDevice.hpp"

#include <algorithm>
#include <cmath>

#include "uhaptics/core/finite_difference.hpp"
#include "uhaptics/core/regularized_solve.hpp"

namespace chai3d {
namespace {

constexpr int kGrid = 21;  // samples per finger joint when surveying the working range
// [N] a fingertip pull above this is a contact: the session statistics' contact threshold
// (uhaptics::SessionStats' default, which cUhapticsDevice uses).
constexpr double kContactThreshold = 0.05;

}  // namespace

cExoFingerDevice::cExoFingerDevice(unsigned int a_deviceNumber, const uhaptics::DeviceSelection& a_selection)
    : cUhapticsDevice(a_deviceNumber, a_selection, 1.0 / 500.0, Model::kJoints, Model::kActuated),
      m_model(std::make_unique<Model>(Model::load(paramsDirectory() + "/exo_finger.json"))),
      m_couplingStiffness(a_selection.option("coupling_stiffness", 1.0, 1e-3, 100.0)),
      m_standardMethod(a_selection.option("method", 0.0, 0.0, 1.0) == 1.0) {
  const Model& model = *m_model;
  // Survey the working range: fingertip extent (workspace), actuator lever |d x / d l_x| (for Z_q)
  // and fingertip displacement per actuator length (for the force the device can show).
  uhaptics::Vec2 lo = uhaptics::Vec2::Constant(1e9), hi = uhaptics::Vec2::Constant(-1e9);
  double lever_sq = 0.0, tip_per_length = 0.0, tip_lever_sq = 0.0;
  int samples = 0;
  for (int i = 0; i < kGrid; ++i) {
    for (int j = 0; j < kGrid; ++j) {
      const Model::TaskVector x = model.taskLower() + (model.taskUpper() - model.taskLower()).cwiseProduct(
                                                          uhaptics::Vec2(i / (kGrid - 1.0), j / (kGrid - 1.0)));
      Model::JointVector q;
      if (!model.inverse(x, q)) continue;
      const uhaptics::Vec2 tip = fingertip(x);
      lo = lo.cwiseMin(tip);
      hi = hi.cwiseMax(tip);
      Model::Jacobian J;
      model.jacobian(q, J);
      const uhaptics::Mat2 Jtip = uhaptics::centralDifferenceJacobian([&](const uhaptics::Vec2& y) { return fingertip(y); }, x);
      lever_sq += J.col(0).squaredNorm();
      tip_per_length += (Jtip * J.col(0)).norm();
      tip_lever_sq += 0.5 * Jtip.squaredNorm();
      ++samples;
    }
  }
  if (samples == 0) throw uhaptics::Error("exo finger: no configuration of the working range assembles");
  lever_sq /= samples;
  tip_per_length /= samples;
  tip_lever_sq /= samples;
  m_centre = 0.5 * (lo + hi);
  const double radius = 0.5 * (hi - lo).minCoeff();

  setCommonSpecifications("finger exoskeleton module", false);
  // Virtual work: F_tip |d tip| = F_act |d l_x|, on average over the working range.
  m_specifications.m_maxLinearForce = model.effortLimits()(0) / tip_per_length;
  // What an application may ask of the proxy: the coupling stiffness seen at the fingertip.
  m_specifications.m_maxLinearStiffness = m_couplingStiffness / tip_lever_sq;
  m_specifications.m_maxLinearDamping = 0.0;  // a position-driven finger: nothing to damp
  m_specifications.m_workspaceRadius = radius;
  m_specifications.m_leftHand = false;

  uhaptics::UnderactuatedGains<Model> gains;
  gains.Zx = m_couplingStiffness * uhaptics::Mat2::Identity();
  gains.Zq = Model::ActuatorVector::Constant(m_couplingStiffness * lever_sq).asDiagonal();  // Z_x seen at l_x
  gains.force_limit = model.effortLimits();
  m_renderer = std::make_unique<Renderer>(model, gains);
  m_standard = std::make_unique<uhaptics::StandardRenderer<Model>>(model, gains);

  using Kind = uhaptics::RendererFigure::Kind;
  m_figureContactTicks = sessionStats().declareFigure("proxy_contact_ticks", Kind::kCount);
  m_figureProxyDistance = sessionStats().declareFigure("max_proxy_distance_mm", Kind::kMaximum);
  m_figureActuatorForce = sessionStats().declareFigure("max_actuator_force_N", Kind::kMaximum);
  m_figureSolves = sessionStats().declareFigure("proxy_solves", Kind::kCount);
  m_figureActiveImpedance = sessionStats().declareFigure("active_impedance_ticks", Kind::kCount);
}

cExoFingerDevice::~cExoFingerDevice() { close(); }

uhaptics::Vec2 cExoFingerDevice::fingertip(const Model::TaskVector& a_x) const noexcept {
  uhaptics::ExoFingerPoints points;
  m_model->points(a_x, points);
  return points.fingertip;
}

uhaptics::Mat2 cExoFingerDevice::fingertipJacobian(const Model::TaskVector& a_x) const noexcept {
  // fingertip = L_p u(q_MCP) + L_m u(q_MCP + q_PIP), u(a) = (cos a, sin a): differentiated in closed form.
  const uhaptics::ExoFingerGeometry& g = m_model->geometry();
  const double a = a_x(0), b = a_x(0) + a_x(1);
  const uhaptics::Vec2 distal = g.middle_length * uhaptics::Vec2(-std::sin(b), std::cos(b));
  uhaptics::Mat2 J;
  J.col(0) = g.proximal_length * uhaptics::Vec2(-std::sin(a), std::cos(a)) + distal;
  J.col(1) = distal;
  return J;
}

void cExoFingerDevice::updateState(double a_dt) noexcept {
  // Hand frame (x distal) -> device y-z plane, see the class comment.
  const uhaptics::Vec3 position = planarToDevice(m_data.points.fingertip - m_centre);
  m_state.linearVelocity = a_dt > 0.0 ? ((position - m_state.position) / a_dt).eval() : uhaptics::Vec3::Zero();
  m_state.position = position;
  m_state.joints = m_data.q;  // l_x [m], q_B [rad]
}

std::unique_ptr<uhaptics::BoardPlant> cExoFingerDevice::makeSimulatedPlant() {
  const Model& model = *m_model;
  // The user, for half an hour (the sim's longest; then the finger rests): with a hand path chosen
  // for the scene, the finger whose fingertip follows it as closely as the finger can; otherwise
  // paper 000's flexion-extension cycles; a finger held still when the hand is off. The finger is
  // position-driven: the hand's force has nothing to move.
  const auto fingerTrajectory = [&]() {
    const Model::TaskVector rest = 0.5 * (model.taskLower() + model.taskUpper());
    if (!getScriptedHandEnabled()) return uhaptics::FingerTrajectory::fromSamples(model, {0.0, 1.0}, {rest, rest}, "finger at rest");
    if (!m_selection.hand_path_given) {
      return uhaptics::FingerTrajectory::synthesized(model, 1800.0, m_selection.hand.lap_time, 20.0);
    }
    const uhaptics::ScriptedHand hand(m_selection.hand, m_specifications.m_workspaceRadius, uhaptics::Vec3::Zero());
    return uhaptics::FingerTrajectory::followingPath(
        model,
        [&](double a_t) {
          uhaptics::Vec3 anchor, velocity;
          hand.anchor(a_t, anchor, velocity);
          return uhaptics::Vec2(deviceToPlanar(anchor) + m_centre);  // device frame -> hand frame
        },
        m_selection.hand.lap_time, 1800.0, 50.0);
  };
  uhaptics::ExoFingerSimOptions options;
  options.update_rate_hz = 1.0 / getServoPeriod();
  options.force_loop_lag = m_selection.option("force_loop_lag", 1.0, 0.0, 1.0) != 0.0;
  auto plant = std::make_unique<uhaptics::ExoFingerBoardPlant>(std::make_unique<const Model>(model), fingerTrajectory(), options);
  m_plant = plant.get();  // owned by the joint I/O until close()
  return plant;
}

void cExoFingerDevice::resetRendering() {
  m_renderer->reset();
  m_actuator.setZero();
}

void cExoFingerDevice::endSession() noexcept {
  m_actuator.setZero();
  m_fingerTorqueCommand.setZero();
  m_plant = nullptr;
}

void cExoFingerDevice::sense(const JointReading& a_reading) noexcept {
  m_model->forward(Eigen::Map<const Model::JointVector>(a_reading.positions), m_data);
  updateState(a_reading.first ? 0.0 : getServoPeriod());
}

uhaptics::Fault cExoFingerDevice::render(const ServoInput& a_input, double* a_efforts) noexcept {
  // The proxy pull in the finger plane (device y, z) -> hand frame -> finger-joint torque.
  const uhaptics::Vec2 f_hand = deviceToPlanar(a_input.force);
  const bool pulled = !f_hand.isZero(0.0);
  uhaptics::Mat2 Jtip = uhaptics::Mat2::Zero();  // d fingertip / d x, hand frame; only with a command
  if (pulled || !m_fingerTorqueCommand.isZero(0.0)) Jtip = fingertipJacobian(m_data.x);
  Model::TaskVector x_proxy = m_data.x;
  if (pulled) x_proxy += (Jtip.transpose() * f_hand) / m_couplingStiffness;
  x_proxy += m_fingerTorqueCommand / m_couplingStiffness;  // multi-point tools' joint torque
  // The renderer solves for the subspace proxy exactly when it has a proxy off the probe to render
  // and none of its input checks fails (the same checks, on the same model evaluations of q): in
  // free space (no force, no joint torque) the proxy is the probe and every solve is skipped.
  const bool solves = !(x_proxy - m_data.x).isZero(0.0) && x_proxy.allFinite() && m_data.q.allFinite() &&
                      m_data.in_range && m_data.x.allFinite() && m_data.J.allFinite();
  // The sensed state's kinematics (sense()) are the renderer's: it evaluates the model only to solve.
  const uhaptics::Fault fault =
      m_standardMethod ? m_standard->tick(m_data.q, x_proxy, m_data.x, m_data.J, m_data.in_range, m_actuator)
                       : m_renderer->tick(m_data.q, x_proxy, m_data.x, m_data.J, m_data.in_range, m_actuator);
  const double magnitude = std::abs(m_actuator(0));
  if (solves) {
    sessionStats().count(m_figureSolves);
    const double distance = (fingertip(x_proxy) - m_data.points.fingertip).norm();  // probe f(q) to proxy
    sessionStats().observeMaximum(m_figureProxyDistance, 1e3 * distance);
    // The application's pull as one fingertip force: the joint torque it asks for, Z_x (x_p - x),
    // through J_tip^-T (the Cartesian force itself when only that channel is used).
    const uhaptics::Vec2 pull =
        uhaptics::regularizedSolve(Jtip.transpose(), m_couplingStiffness * (x_proxy - m_data.x));
    if (fault == uhaptics::Fault::kNone && pull.norm() > kContactThreshold) {
      sessionStats().count(m_figureContactTicks);
      // Passivity of what the method displays here: the symmetric part of d tau / d q must not
      // have a positive eigenvalue (relative to the impedance's size: rounding is not activity).
      const uhaptics::Mat2 Z = m_standardMethod ? m_standard->displayedImpedance() : m_renderer->displayedImpedance();
      const uhaptics::Mat2 symmetric = 0.5 * (Z + Z.transpose());
      const double trace = symmetric.trace(), det = symmetric.determinant();
      const double largest = 0.5 * trace + std::sqrt(std::max(0.0, 0.25 * trace * trace - det));
      if (largest > 1e-9 * Z.norm()) sessionStats().count(m_figureActiveImpedance);
    }
  }
  sessionStats().observeMaximum(m_figureActuatorForce, magnitude);
  Eigen::Map<Model::ActuatorVector> out(a_efforts);
  out = m_actuator;
  return fault;
}

uhaptics::Vec2 cExoFingerDevice::getFingerAngles() {
  std::lock_guard<std::mutex> lock(deviceMutex());
  return m_data.x;
}

uhaptics::ExoFingerPoints cExoFingerDevice::getFingerPoints() {
  std::lock_guard<std::mutex> lock(deviceMutex());
  return m_data.points;
}

double cExoFingerDevice::getActuatorForce() {
  std::lock_guard<std::mutex> lock(deviceMutex());
  return m_actuator(0);
}

uhaptics::Vec3 cExoFingerDevice::handToDevice(const uhaptics::Vec2& a_handPoint) const noexcept {
  return planarToDevice(a_handPoint - m_centre);
}

void cExoFingerDevice::setFingerJointTorque(const uhaptics::Vec2& a_torque) {
  std::lock_guard<std::mutex> lock(deviceMutex());
  m_fingerTorqueCommand = a_torque.allFinite() ? a_torque : uhaptics::Vec2::Zero();
}

uhaptics::Vec2 cExoFingerDevice::getFingerJointTorque() {
  std::lock_guard<std::mutex> lock(deviceMutex());
  return m_fingerTorqueCommand;
}

uhaptics::Vec2 cExoFingerDevice::getFingerTorque() {
  std::lock_guard<std::mutex> lock(deviceMutex());
  // On emulated the plant runs inside the board emulator, in the servo thread: not ours to read.
  return m_plant && !rendersInServoThread() ? m_plant->sim().state().finger_torque : uhaptics::Vec2::Zero();
}

}  // namespace chai3d
