#pragma once
// Test fixture (not a product device): a 3-DoF point mass with viscous friction and per-axis force
// limits, enough to exercise everything cUhapticsDevice does around a device: the servo cycle over
// a sim joint I/O, the clock, the scripted hand, statistics, faults, the CHAI3D contract. Its
// renderer is the identity (the application's force goes straight to the actuators, limited by the
// joint I/O's safety stage), so CHAI3D's own proxy forces are what the mass feels.
#include <algorithm>
#include <cmath>
#include <memory>

#include "uhaptics/chai3d/CUhapticsDevice.hpp"

// The point mass as its own simulated plant: three prismatic joints, all actuated.
class PointMassPlant final : public uhaptics::BoardPlant {
 public:
  static constexpr double kMass = 0.2;        // [kg]
  static constexpr double kFriction = 2.0;    // [N s/m]

  int jointCount() const noexcept override { return 3; }
  int actuatorCount() const noexcept override { return 3; }
  void readJoints(double* positions) noexcept override {
    Eigen::Map<uhaptics::Vec3> out(positions);
    out = position;
  }
  void applyCommand(const double* efforts) noexcept override { actuator = Eigen::Map<const uhaptics::Vec3>(efforts); }
  void setUserForce(const uhaptics::Vec3& force) noexcept override { user = force; }
  void advance(double dt) noexcept override {
    const uhaptics::Vec3 acceleration = (actuator + user - kFriction * velocity) / kMass;
    velocity += dt * acceleration;  // semi-implicit Euler: stable for this stiffness and step
    position += dt * velocity;
  }

  uhaptics::Vec3 position = uhaptics::Vec3::Zero();
  uhaptics::Vec3 velocity = uhaptics::Vec3::Zero();
  uhaptics::Vec3 actuator = uhaptics::Vec3::Zero();  // as applied, after the safety stage
  uhaptics::Vec3 user = uhaptics::Vec3::Zero();
};

// The identity policy: the scene's force goes straight to the three actuators.
class PointMassPolicy final : public uhaptics::DevicePolicy {
 public:
  std::string name() const override { return "identity"; }
  void reset(int) override {}
  void sense(const uhaptics::SensedJoints& reading, uhaptics::SensedState& state) noexcept override {
    state.position = Eigen::Map<const uhaptics::Vec3>(reading.positions);
    state.linear_velocity = Eigen::Map<const uhaptics::Vec3>(reading.rates);
    state.joints = state.position;  // three prismatic "joints"
  }
  uhaptics::Fault render(const uhaptics::SceneInput& input, double* efforts) noexcept override {
    Eigen::Map<uhaptics::Vec3> out(efforts);
    out = input.force;
    return uhaptics::Fault::kNone;
  }
  bool actuatedInertia(double* inertia) const override {
    Eigen::Map<Eigen::Matrix3d> out(inertia);
    out = PointMassPlant::kMass * Eigen::Matrix3d::Identity();
    return true;
  }
};

class PointMassDevice : public chai3d::cUhapticsDevice {
 public:
  static constexpr double kMass = PointMassPlant::kMass;
  static constexpr double kFriction = PointMassPlant::kFriction;
  static constexpr double kMaxForce = 10.0;   // [N] per axis

  explicit PointMassDevice(const uhaptics::DeviceSelection& selection)
      : cUhapticsDevice(0, selection, 1e-3, 3, 3) {
    const double rest[3] = {0.0, 0.0, 0.0};
    setPolicy(std::make_unique<PointMassPolicy>(), rest);
    setCommonSpecifications("point mass (test fixture)", false);
    m_specifications.m_maxLinearForce = kMaxForce;
    m_specifications.m_maxLinearStiffness = 2000.0;
    m_specifications.m_maxLinearDamping = 10.0;
    m_specifications.m_workspaceRadius = 0.1;
  }
  ~PointMassDevice() override { close(); }

  /// The simulated point mass (valid while the device is open).
  const PointMassPlant& plant() const { return *plant_; }

 protected:
  std::unique_ptr<uhaptics::JointIo> makeJointIo() override {
    uhaptics::BoardSpec spec;
    spec.descriptor.name = "point mass";
    spec.descriptor.joints = 3;
    spec.descriptor.actuators = 3;
    std::fill(spec.descriptor.effort_limit.begin(), spec.descriptor.effort_limit.begin() + 3, kMaxForce);
    spec.servo_rate_hz = spec.sample_rate_hz = 1000.0;
    return uhaptics::makeSimJointIo(spec, [this] { return makeSimulatedPlant(); });
  }
  std::unique_ptr<uhaptics::BoardPlant> makeSimulatedPlant() override {
    auto plant = std::make_unique<PointMassPlant>();
    plant_ = plant.get();
    return plant;
  }

 private:
  PointMassPlant* plant_ = nullptr;  // owned by the joint I/O
};
