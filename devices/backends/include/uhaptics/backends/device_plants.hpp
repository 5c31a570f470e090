#pragma once
// What the devices' simulated plants share (each device's plant is in its folder,
// devices/<device>/backend/): a fixed-step clock that turns any elapsed time into whole simulation
// steps, and the base of plants whose joints are all actuated with the torque held between updates.
// A plant is a device's simulation seen as what its controller board drives (BoardPlant), so the
// board emulator speaks the wire protocol on top of the real device simulation and the same plant
// serves as the "sim" joint I/O (joint_io.hpp). Allocation-free and noexcept after construction.
#include <memory>

#include "uhaptics/backends/board_plant.hpp"
#include "uhaptics/core/types.hpp"

namespace uhaptics {

/// Turns an arbitrary elapsed time into whole simulation steps of a fixed period. At most
/// max_catch_up seconds of simulation are due per call; an older backlog is dropped (the simulated
/// device then runs behind the wall clock), so a simulation slower than real time (a sanitizer
/// build, a stalled machine) cannot spiral into ever longer catch-up calls.
class FixedStepClock {
 public:
  /// Throws Error unless period and max_catch_up are finite and period > 0, max_catch_up >= period.
  explicit FixedStepClock(double period, double max_catch_up = 0.02);
  /// Adds dt (negative or non-finite dt is ignored) and returns how many whole periods are due.
  long take(double dt) noexcept;
  double period() const noexcept { return period_; }
  /// Simulation time dropped so far [s].
  double dropped() const noexcept { return dropped_; }

 private:
  double period_;
  long max_steps_;
  double pending_ = 0.0;
  double dropped_ = 0.0;
};

/// Plants whose joints are all actuated, with the torque held between updates (TAU, RHI).
template <int N>
class HeldTorquePlant : public BoardPlant {
 public:
  int jointCount() const noexcept override { return N; }
  int actuatorCount() const noexcept override { return N; }
  void readJoints(double* positions) noexcept override {
    Eigen::Map<Vec<N>> out(positions);
    out = sensed();
  }
  void applyCommand(const double* efforts) noexcept override { command_ = Eigen::Map<const Vec<N>>(efforts); }

 protected:
  virtual const Vec<N>& sensed() const noexcept = 0;
  Vec<N> command_ = Vec<N>::Zero();
};

}  // namespace uhaptics
