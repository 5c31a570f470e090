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
    setCommonSpecifications("point mass (test fixture)", false);
    m_specifications.m_maxLinearForce = kMaxForce;
    m_specifications.m_maxLinearStiffness = 2000.0;
    m_specifications.m_maxLinearDamping = 10.0;
    m_specifications.m_workspaceRadius = 0.1;
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
    publish();
  }
  void stopBackend() noexcept override { last_actuator_.setZero(); }
  uhaptics::Fault servoTick(const ServoInput& input, double& output) noexcept override {
    const double dt = input.dt;
    last_actuator_ = input.force;
    uhaptics::scaleIntoBox(last_actuator_, uhaptics::Vec3::Constant(kMaxForce));
    output = last_actuator_.cwiseAbs().maxCoeff();
    const uhaptics::Vec3 acceleration = (last_actuator_ + input.handForce - kFriction * velocity_) / kMass;
    velocity_ += dt * acceleration;  // semi-implicit Euler: stable for this stiffness and step
    position_ += dt * velocity_;
    publish();
    return uhaptics::Fault::kNone;
  }

 private:
  void publish() noexcept {
    m_state.position = position_;
    m_state.linearVelocity = velocity_;
    m_state.joints = position_;  // three prismatic "joints"
  }
};
