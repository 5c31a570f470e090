#pragma once
// Test fixture (not a product device): a 3-DoF point mass with viscous friction and per-axis force
// saturation, enough to exercise everything cUhapticsDevice does around a device: the clock, the
// scripted hand, statistics, faults, the CHAI3D contract. Its renderer is the identity (the
// application's force goes straight to the actuators), so CHAI3D's own proxy forces are what the
// mass feels.
#include <algorithm>
#include <cmath>

#include "uhaptics/chai3d/CUhapticsDevice.hpp"
#include "uhaptics/core/limits.hpp"

class PointMassDevice : public chai3d::cUhapticsDevice {
 public:
  static constexpr double kMass = 0.2;        // [kg]
  static constexpr double kFriction = 2.0;    // [N s/m]
  static constexpr double kMaxForce = 10.0;   // [N] per axis

  explicit PointMassDevice(const uhaptics::DeviceSelection& selection)
      : cUhapticsDevice(0, selection, 1e-3) {
    setCommonSpecifications("point mass (test fixture)");
    m_specifications.m_maxLinearForce = kMaxForce;
    m_specifications.m_maxAngularTorque = 0.0;
    m_specifications.m_maxLinearStiffness = 2000.0;
    m_specifications.m_maxAngularStiffness = 0.0;
    m_specifications.m_maxLinearDamping = 10.0;
    m_specifications.m_maxAngularDamping = 0.0;
    m_specifications.m_workspaceRadius = 0.1;
    m_specifications.m_sensedPosition = true;
    m_specifications.m_sensedRotation = false;
    m_specifications.m_actuatedPosition = true;
    m_specifications.m_actuatedRotation = false;
    m_specifications.m_rightHand = true;
    m_specifications.m_leftHand = true;
  }
  ~PointMassDevice() override { close(); }

  std::string getRendererName() const override { return "identity"; }
  uhaptics::Vec3 position_ = uhaptics::Vec3::Zero();
  uhaptics::Vec3 velocity_ = uhaptics::Vec3::Zero();
  uhaptics::Vec3 last_actuator_ = uhaptics::Vec3::Zero();

 protected:
  void startBackend() override {
    position_.setZero();
    velocity_.setZero();
  }
  void stopBackend() noexcept override { last_actuator_.setZero(); }
  uhaptics::Fault servoTick(const uhaptics::Vec3& force, const uhaptics::Vec3&, const uhaptics::Vec3& hand,
                            double dt, double& output) noexcept override {
    last_actuator_ = force;
    uhaptics::scaleIntoBox(last_actuator_, uhaptics::Vec3::Constant(kMaxForce));
    output = last_actuator_.cwiseAbs().maxCoeff();
    const uhaptics::Vec3 acceleration = (last_actuator_ + hand - kFriction * velocity_) / kMass;
    velocity_ += dt * acceleration;  // semi-implicit Euler: stable for this stiffness and step
    position_ += dt * velocity_;
    return uhaptics::Fault::kNone;
  }
  void readState(uhaptics::Vec3& p, uhaptics::Mat3& r, uhaptics::Vec3& v, uhaptics::Vec3& w) noexcept override {
    p = position_;
    r.setIdentity();
    v = velocity_;
    w.setZero();
  }
  int readJointAngles(double q[chai3d::C_MAX_DOF]) noexcept override {
    for (int i = 0; i < 3; ++i) q[i] = position_(i);
    return 3;
  }
};
