#pragma once
// uhaptics::DevicePolicy: how one device renders a scene, written once per device and run by every
// caller: the CHAI3D adapter (cUhapticsDevice, in the board's servo thread or the simulation's
// tick), the servo tool and its end-to-end tests (tools/servo, with a scripted scene).
//
// One servo period, on every backend:
//
//   joint reading -> sense() (kinematics: what the scene sees) -> render(scene input) -> efforts
//
// The policy sees the joints as the sensors give them (encoder counts times their resolution) and
// rates from the caller's rate estimator: nothing a board would not report. Frames: the scene's
// device frame (CHAI3D's: x toward the operator, y to the right, z up; origin at the workspace
// centre). The policy maps it to its model's task frame; the *ToDevice/*ToModel members say how,
// for a simulated user who pushes the model's plant.
//
// Threading: a policy is single-threaded; the caller serializes every member (the adapter holds
// its device mutex). sense(), render(), readingLost() and endSession() are the servo tick's: they
// never allocate, throw or block. reset() is set-up.
#include <cstdint>
#include <string>

#include "uhaptics/core/fault.hpp"
#include "uhaptics/core/types.hpp"

namespace uhaptics {

/// The most joints a policy reports (CHAI3D's C_MAX_DOF).
inline constexpr int kMaxSensedJoints = 16;

/// What a policy's figures are: a count of events, the maximum of a value, or a value's latest
/// reading (a running total that may fall, e.g. the net energy a device has given out).
enum class FigureKind { kCount, kMaximum, kValue };

/// Where a policy records the figures that show its method at work (the adapter's session
/// statistics, SessionStats; none() where nobody reads them).
class FigureRecorder {
 public:
  virtual ~FigureRecorder() = default;
  /// Set-up: declares a figure (name: a string literal) and returns its id for the tick's calls.
  /// Throws uhaptics::Error when the recorder is full or the name is taken.
  virtual int declareFigure(const char* name, FigureKind kind) = 0;
  /// Servo tick: adds n to a count / raises a maximum / sets a value (non-finite values are ignored).
  virtual void count(int id, std::uint64_t n = 1) noexcept = 0;
  virtual void observeMaximum(int id, double value) noexcept = 0;
  virtual void setValue(int id, double value) noexcept = 0;
  /// A recorder that keeps nothing (ids are valid, values are dropped).
  static FigureRecorder& none() noexcept;
};

/// One joint reading.
struct SensedJoints {
  const double* positions;  // [rad, or m for prismatic joints], as the sensors give them
  const double* rates;      // the caller's estimate [rad/s or m/s] (zero on the session's first reading)
  bool first;               // the session's first reading
};

/// What the device senses, device frame, origin at the workspace centre.
struct SensedState {
  Vec3 position = Vec3::Zero();                   // [m]
  Mat3 rotation = Mat3::Identity();               // identity for devices that sense none
  Vec3 linear_velocity = Vec3::Zero();            // [m/s]
  Vec3 angular_velocity = Vec3::Zero();           // [rad/s]
  /// Sensed joints (actuated and sensed-only) in the device's joint order; no heap.
  Eigen::Matrix<double, Eigen::Dynamic, 1, Eigen::ColMajor, kMaxSensedJoints, 1> joints;
};

/// What the scene asks of one servo period.
struct SceneInput {
  Vec3 force = Vec3::Zero();          // [N], device frame, on the tool
  Vec3 torque = Vec3::Zero();         // [N m]
  Vec3 seen_position = Vec3::Zero();  // [m] the position the scene computed them from
  double dt = 0.0;                    // the servo period [s]
  double time = 0.0;                  // servo ticks so far x dt [s]
};

/// Maps between the scene's device frame and the planar devices' task plane: planar devices (the
/// exoskeleton finger, the planar linkages) work in the device frame's y-z plane, task x -> +y,
/// task y -> -z; the device x axis is never sensed nor actuated.
inline Vec3 planarToDevice(const Vec2& task) noexcept { return Vec3(0.0, task.x(), -task.y()); }
inline Vec2 deviceToPlanar(const Vec3& device) noexcept { return Vec2(device.y(), -device.z()); }
/// A device-frame force in a planar model's task frame (x, y, 0).
inline Vec3 planarForce(const Vec3& device) noexcept { return Vec3(device.y(), -device.z(), 0.0); }

class DevicePolicy {
 public:
  virtual ~DevicePolicy() = default;

  /// The rendering method now in use (it may change at run time, e.g. the TAU's wall).
  virtual std::string name() const = 0;
  /// Before a session's first reading: filters and renderers to their initial state, designed for
  /// command_delay periods between the reading sense() gets and the period render()'s efforts act
  /// in (0 on the simulation, 1 over the board protocol). May allocate; throws uhaptics::Error when
  /// a design fails.
  virtual void reset(int command_delay) = 0;
  /// The kinematics of a reading, for render() and for the scene (state).
  virtual void sense(const SensedJoints& reading, SensedState& state) noexcept = 0;
  /// After the session's first sense(): throws uhaptics::Error when the device cannot start there.
  virtual void checkFirstReading() const {}
  /// One servo period from the last sense(): the actuator efforts for the scene's input. A
  /// returned fault (or a non-finite effort) makes the caller send zero instead.
  virtual Fault render(const SceneInput& input, double* efforts) noexcept = 0;
  /// A period without a reading, or without current input from the scene: render() was not
  /// called; end what assumes a continuous contact.
  virtual void readingLost() noexcept {}
  /// The session ended (the last command was zero).
  virtual void endSession() noexcept {}
  /// Servo tick, before render(): the board named the command it applied over the period the last
  /// reading ends (its STATE's last_command_sequence): periods_ago render() calls before the newest
  /// (0: the last render()'s efforts). Ignored by policies whose design assumes a fixed delay.
  virtual void commandApplied(int periods_ago) noexcept { (void)periods_ago; }

  /// Servo tick, after render(): adds to `efforts` (one per actuator, zeroed by the caller) the share
  /// of render()'s efforts that is the policy's own field rather than the scene's force: gravity
  /// compensation, null-space control, a position controller's regulator around its surface. The
  /// rest renders the scene, and the passivity layer observes that share alone (PassivePolicy). By
  /// default none: every effort renders the scene.
  virtual void ownEfforts(double* efforts) const noexcept { (void)efforts; }
  /// Set-up: the joint-space inertia of the actuated joints at the last sensed configuration [kg m^2,
  /// kg on a prismatic joint], column-major, actuators x actuators, into `inertia`; false (nothing
  /// written) when the policy's model states no dynamics. Sizes the passivity layer's damping cap.
  virtual bool actuatedInertia(double* inertia) const {
    (void)inertia;
    return false;
  }

  /// The scene's device-frame force in the model's task frame (where a simulated user pushes the
  /// model's plant); unchanged by default.
  virtual Vec3 deviceToModelForce(const Vec3& force) const noexcept { return force; }
  /// The scene's device-frame force at the port where the simulated plant states its truth
  /// (PlantTruth, for the referee): the model's task frame by default (deviceToModelForce). A device
  /// whose user holds it elsewhere than at the scene's tool point says here what the scene asked of
  /// that port. Called after render() in the same period.
  virtual Vec3 sceneForceAtUserPort(const Vec3& force) const noexcept { return deviceToModelForce(force); }
  /// A point [m] and a vector of the model's task frame in the device frame; unchanged by default.
  virtual Vec3 modelToDevicePoint(const Vec3& point) const noexcept { return point; }
  virtual Vec3 modelToDeviceVector(const Vec3& vector) const noexcept { return vector; }
};

}  // namespace uhaptics
