#pragma once
// What a controller board sees of its device: joint sensors to sample, actuators to drive, time.
// The board emulator runs its firmware logic on top of a BoardPlant; a simulated device backend
// (devices/backends) becomes a BoardPlant through a small adapter, and LinearTestPlant below is a
// self-contained plant for the protocol and servo-loop tests.
//
// All methods are called from one thread (the emulator's), never allocate and never throw.
#include <array>

#include "uhaptics/core/fault.hpp"
#include "uhaptics/core/types.hpp"
#include "uhaptics/protocol/wire_protocol.hpp"

namespace uhaptics {

/// The simulated device as it is where its user holds it, for the referee (referee.hpp) and nothing
/// else: no rendering policy ever reads it. Device model task frame (planar devices: x, y, 0).
struct PlantTruth {
  Vec3 position = Vec3::Zero();       // [m] where the user holds the device
  Vec3 velocity = Vec3::Zero();       // [m/s]
  Vec3 user_force = Vec3::Zero();     // [N] the user's force on the device there, this period
  /// [N] the force the actuators' efforts, as applied (after the board's limits and delay), exert
  /// there in statics, beyond holding up the device's own weight: what the user feels in a hold.
  Vec3 applied_force = Vec3::Zero();
  bool saturated = false;             // an actuator is at its effort limit
};

class BoardPlant {
 public:
  virtual ~BoardPlant() = default;
  virtual int jointCount() const noexcept = 0;
  virtual int actuatorCount() const noexcept = 0;
  /// Current sensor values (rad or m), jointCount() entries.
  virtual void readJoints(double* positions) noexcept = 0;
  /// Actuator efforts (N m or N), actuatorCount() entries, held until the next call.
  virtual void applyCommand(const double* efforts) noexcept = 0;
  /// Integrates the plant over dt seconds with the held command.
  virtual void advance(double dt) noexcept = 0;

  // What a simulation offers beyond a board: a user the caller simulates. Nothing else: the host
  // sees a simulated or emulated device exactly as a board's sensors report it.
  /// Where the simulated user holds the device: the end effector's position [m] and velocity [m/s]
  /// in the device model's task frame (planar devices: x, y, 0) as they are, without sensor error:
  /// a hand feels the device as it is, not as its encoders report it. False when the plant has no
  /// such point for a caller's user (a position-driven user of its own).
  virtual bool readUserPoint(Vec3& position, Vec3& velocity) noexcept {
    (void)position;
    (void)velocity;
    return false;
  }
  /// The force [N] of a user the caller simulates (a CHAI3D session's scripted hand) on the end
  /// effector, in the device model's task frame (planar devices: x, y), held until the next call.
  /// Only plants made without a user of their own take it; a position-driven user (the finger in
  /// the exoskeleton) ignores it.
  virtual void setUserForce(const Vec3& force) noexcept { (void)force; }
  /// The referee's view (PlantTruth) after the last advance(); false where the plant has none.
  virtual bool readTruth(PlantTruth& truth) noexcept {
    (void)truth;
    return false;
  }
  /// The force [N] the scene asks the device to render this period (model task frame), for the
  /// referee only: a plant moves by its actuators and its user, never by this.
  virtual void setSceneForce(const Vec3& force) noexcept { (void)force; }
  /// The simulation's fault in the last advance() (kNone: it stepped as modelled).
  virtual Fault lastFault() const noexcept { return Fault::kNone; }
};

/// Decoupled mass-spring-dampers, one per actuator (m q'' + b q' + k q = u); sensed-only joints
/// beyond the actuated ones follow a fixed fraction of actuator 0 (a passive linkage, as the finger
/// exoskeleton's q_B does). Semi-implicit Euler with 0.1 ms substeps: stable for the defaults.
class LinearTestPlant final : public BoardPlant {
 public:
  struct Params {
    int joints = 2;
    int actuators = 1;
    double mass = 0.05;        // kg or kg m^2
    double damping = 0.5;      // N s/m
    double stiffness = 50.0;   // N/m: a soft centring spring, so commanded efforts give bounded motion
    double passive_ratio = 0.5;
  };
  explicit LinearTestPlant(const Params& p) noexcept;

  int jointCount() const noexcept override { return params_.joints; }
  int actuatorCount() const noexcept override { return params_.actuators; }
  void readJoints(double* positions) noexcept override;
  void applyCommand(const double* efforts) noexcept override;
  void advance(double dt) noexcept override;

  /// Last effort applied to actuator i (what the test inspects: "zero torque within N periods").
  double appliedEffort(int i) const noexcept { return effort_[i]; }

 private:
  Params params_;
  std::array<double, wire::kMaxChannels> q_{}, qd_{}, effort_{};
};

}  // namespace uhaptics
