#include "uhaptics/chai3d/CExoFingerDevice.hpp"

#include <cmath>

namespace chai3d {
namespace {

uhaptics::ExoFingerPolicy::Options policyOptions(const uhaptics::DeviceSelection& a_selection, double a_servoPeriod) {
  uhaptics::ExoFingerPolicy::Options options;
  options.coupling_stiffness = a_selection.option("coupling_stiffness", 1.0, 1e-3, 100.0);
  // 0, 1, 2: the order of ExoFingerPolicy::Method.
  options.method = static_cast<uhaptics::ExoFingerPolicy::Method>(std::lround(a_selection.option("method", 0.0, 0.0, 2.0)));
  options.servo_period = a_servoPeriod;
  return options;
}

}  // namespace

cExoFingerDevice::cExoFingerDevice(unsigned int a_deviceNumber, const uhaptics::DeviceSelection& a_selection)
    : cUhapticsDevice(a_deviceNumber, a_selection, 1.0 / 500.0, Model::kJoints, Model::kActuated) {
  auto policy = std::make_unique<uhaptics::ExoFingerPolicy>(Model::load(paramsDirectory() + "/exo_finger.json"),
                                                            policyOptions(a_selection, getServoPeriod()), sessionStats());
  m_exo = policy.get();
  const Model& model = m_exo->model();
  Model::JointVector rest;  // the middle of the finger's range, until opened
  model.inverse(0.5 * (model.taskLower() + model.taskUpper()), rest);
  setPolicy(std::move(policy), rest.data());

  setCommonSpecifications("finger exoskeleton module", false);
  m_specifications.m_maxLinearForce = m_exo->fingertipForce();
  // What an application may ask of the proxy: the coupling stiffness seen at the fingertip.
  m_specifications.m_maxLinearStiffness = m_exo->fingertipStiffness();
  m_specifications.m_maxLinearDamping = 0.0;  // a position-driven finger: nothing to damp
  m_specifications.m_workspaceRadius = m_exo->workspaceRadius();
  m_specifications.m_leftHand = false;
}

cExoFingerDevice::~cExoFingerDevice() { close(); }

std::unique_ptr<uhaptics::BoardPlant> cExoFingerDevice::makeSimulatedPlant() {
  const Model& model = m_exo->model();
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
          return uhaptics::Vec2(uhaptics::deviceToPlanar(anchor) + m_exo->centre());  // device frame -> hand frame
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

uhaptics::Vec2 cExoFingerDevice::getFingerAngles() {
  std::lock_guard<std::mutex> lock(deviceMutex());
  return m_exo->data().x;
}

uhaptics::ExoFingerPoints cExoFingerDevice::getFingerPoints() {
  std::lock_guard<std::mutex> lock(deviceMutex());
  return m_exo->data().points;
}

double cExoFingerDevice::getActuatorForce() {
  std::lock_guard<std::mutex> lock(deviceMutex());
  return m_exo->actuatorForce();
}

void cExoFingerDevice::setFingerJointTorque(const uhaptics::Vec2& a_torque) {
  std::lock_guard<std::mutex> lock(deviceMutex());
  m_exo->setFingerJointTorque(a_torque);
}

uhaptics::Vec2 cExoFingerDevice::getFingerJointTorque() {
  std::lock_guard<std::mutex> lock(deviceMutex());
  return m_exo->fingerJointTorque();
}

uhaptics::Vec2 cExoFingerDevice::getFingerTorque() {
  std::lock_guard<std::mutex> lock(deviceMutex());
  // On emulated the plant runs inside the board emulator, in the servo thread: not ours to read.
  return m_plant && !rendersInServoThread() ? m_plant->sim().state().finger_torque : uhaptics::Vec2::Zero();
}

}  // namespace chai3d
