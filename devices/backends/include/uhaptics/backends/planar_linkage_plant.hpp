#pragma once
// A planar linkage's simulation as its board drives it: N joint angles [rad], N joint torques [N m]
// (SimulatedPlanarLinkage<N>), for every planar device (paper 003's RHI and its 3-DoF example arm).
// Its user, by default: a grip holding the end effector where it starts (the paper's palpation
// set-up). With a zero grip, the user is whoever calls setUserForce (a CHAI3D session's scripted
// hand).
#include <Eigen/Cholesky>
#include <memory>
#include <string>

#include "uhaptics/backends/device_definition.hpp"
#include "uhaptics/backends/device_plants.hpp"
#include "uhaptics/backends/simulated_planar_linkage.hpp"
#include "uhaptics/core/fault.hpp"
#include "uhaptics/models/planar_linkage_model.hpp"

namespace uhaptics {

template <int N>
class PlanarLinkagePlant final : public HeldTorquePlant<N> {
 public:
  using Model = PlanarLinkageModel<N>;
  struct Options {
    double substep = 1e-4;            // integration step [s]
    double hand_stiffness = 800.0;    // grip holding the end effector at its start [N/m]
    double hand_damping = 8.0;        // [N s/m]
  };
  /// Starts at rest at the model's home configuration. Throws Error on invalid options.
  PlanarLinkagePlant(Model model, const Options& options)
      : sim_(std::move(model), options.substep), clock_(options.substep) {
    if (!(options.hand_stiffness >= 0.0) || !(options.hand_damping >= 0.0))
      throw Error("PlanarLinkagePlant: hand stiffness and damping must be >= 0");
    load_.anchor = sim_.endEffectorPosition();
    load_.stiffness = options.hand_stiffness * Mat2::Identity();
    load_.damping = options.hand_damping * Mat2::Identity();
    sim_.setLoad(load_);
  }

  void advance(double dt) noexcept override {
    const long n = clock_.take(dt);
    if (n > 0) fault_ = sim_.step(this->command_, static_cast<double>(n) * clock_.period());
  }
  bool readUserPoint(Vec3& position, Vec3& velocity) noexcept override {
    position << sim_.endEffectorPosition(), 0.0;
    velocity << sim_.endEffectorVelocity(), 0.0;
    return true;
  }
  void setUserForce(const Vec3& force) noexcept override {
    load_.bias = force.template head<2>();
    sim_.setLoad(load_);
  }
  Fault lastFault() const noexcept override { return fault_; }
  /// The end effector; the user's force is the load on it (grip and setUserForce); the applied force
  /// is the task force of the applied torques, J#^T tau with the dynamically consistent inverse
  /// J# = M^-1 J^T (J M^-1 J^T)^-1 (the rest of tau moves the self-motion, which a hold does not feel).
  bool readTruth(PlantTruth& truth) noexcept override {
    const Model& model = sim_.model();
    const Vec<N>& q = sim_.position();
    const Vec<N>& tau = sim_.appliedTorque();
    typename Model::Jacobian J;
    typename Model::MassMatrix M;
    model.jacobian(q, J);
    model.massMatrix(q, M);
    const Mat<N, 2> minv_jt = Eigen::LLT<Mat<N, N>>(M).solve(J.transpose());
    const Vec2 force = (J * minv_jt).ldlt().solve(minv_jt.transpose() * tau);
    truth.position << sim_.endEffectorPosition(), 0.0;
    truth.velocity << sim_.endEffectorVelocity(), 0.0;
    truth.user_force << sim_.externalForce(), 0.0;
    truth.applied_force << (force.allFinite() ? force : Vec2::Zero()), 0.0;
    truth.saturated = (tau.cwiseAbs().array() >= (1.0 - 1e-9) * model.effortLimits().array()).any();
    return true;
  }

  const SimulatedPlanarLinkage<N>& sim() const noexcept { return sim_; }

 private:
  const Vec<N>& sensed() const noexcept override { return sim_.position(); }
  SimulatedPlanarLinkage<N> sim_;
  FixedStepClock clock_;
  EndEffectorLoad load_;
  Fault fault_ = Fault::kNone;
};

/// The definition parts every planar-linkage device shares, for the model whose parameter file names
/// itself kModel (its "device" field):
///   d.describe_board = &describePlanarLinkageBoard<4, kModel>;
///   d.make_plant = &makePlanarLinkagePlant<4, kModel>;
///   d.make_userless_plant = &makeUserlessPlanarLinkagePlant<4, kModel>;
///   d.hand_damping = PlanarLinkagePlant<4>::Options{}.hand_damping;
template <int N, const char* kModel>
void describePlanarLinkageBoard(const DeviceDefinition& self, const ParamFile& file, BoardSpec& spec) {
  const PlanarLinkageModel<N> model = PlanarLinkageModel<N>::fromParams(file, kModel);
  const Vec<N> limits = model.effortLimits();
  spec.descriptor = DeviceDescriptor::fromParams(file, wire::DeviceType{self.wire_code}, self.title, N, N, limits.data());
}
template <int N, const char* kModel>
std::unique_ptr<BoardPlant> makePlanarLinkagePlant(const std::string& params_path) {
  return std::make_unique<PlanarLinkagePlant<N>>(PlanarLinkageModel<N>::load(params_path, kModel),
                                                 typename PlanarLinkagePlant<N>::Options{});
}
/// Without the grip: the caller's setUserForce is the user. Its 0.1 ms substeps resolve any servo
/// period the harness runs, so step_period changes nothing.
template <int N, const char* kModel>
std::unique_ptr<BoardPlant> makeUserlessPlanarLinkagePlant(const std::string& params_path, double step_period) {
  (void)step_period;
  typename PlanarLinkagePlant<N>::Options options;
  options.hand_stiffness = 0.0;
  options.hand_damping = 0.0;
  return std::make_unique<PlanarLinkagePlant<N>>(PlanarLinkageModel<N>::load(params_path, kModel), options);
}

}  // namespace uhaptics
