// What a CHAI3D application pays per haptic tick: CHAI3D's own cToolCursor tick (finger proxy, AABB
// collision with a 64x64 sphere mesh, free space and 1 mm in contact) on a device that costs
// nothing but has the uhaptics device's specification and position (the same scene scale and
// stiffness), as the reference, and the same tick with each registered uhaptics device behind the tool,
// reached as an unchanged application reaches it: cHapticDeviceHandler -> the custom-device slot ->
// the uhaptics device, in lock-step (every setForceAndTorqueAndGripperForce is one servo tick, the
// case of a 1 kHz application loop).
//
// The device's joint I/O is its simulated one held still (HeldStillJointIo): reads and commands are
// served as a board's would be, but the simulation is not stepped, so what is timed is the plugin
// (sensing, kinematics, renderer, safety stage, statistics, slot, scheduling) and not the plant. The
// uhaptics-report tool turns these runs into the table of docs/benchmarks.md ("CHAI3D tick").
#include <benchmark/benchmark.h>

#include <memory>
#include <string>
#include <vector>

#include "chai3d.h"
#include "uhaptics/chai3d/device_registry.hpp"
#include "uhaptics/tools/alloc_probe.hpp"
#include "chai3d_tick_bench.hpp"

namespace {

using namespace chai3d;

// A device's joint I/O held at the pose it opened in: read() serves that pose with a board's
// advancing sample time, command() is passed on, advance() steps nothing.
class HeldStillJointIo final : public uhaptics::JointIo {
 public:
  explicit HeldStillJointIo(std::unique_ptr<uhaptics::JointIo> inner)
      : JointIo(inner->spec(), inner->backend()), inner_(std::move(inner)) {}
  void open() override {
    inner_->open();
    positions_.assign(static_cast<std::size_t>(spec().descriptor.joints), 0.0);
    if (!inner_->read(positions_.data())) throw uhaptics::Error("HeldStillJointIo: the device gave no first reading");
  }
  void close() noexcept override { inner_->close(); }
  bool isOpen() const noexcept override { return inner_->isOpen(); }
  bool read(double* positions) noexcept override {
    std::copy(positions_.begin(), positions_.end(), positions);
    return true;
  }
  std::uint32_t sampleTimeUs() const noexcept override { return time_us_; }
  void command(const double* efforts) noexcept override { inner_->command(efforts); }
  uhaptics::Fault advance(double dt) noexcept override {
    time_us_ += static_cast<std::uint32_t>(dt * 1e6 + 0.5);
    return uhaptics::Fault::kNone;
  }
  std::string describe() const override { return inner_->describe() + ", held still"; }

 private:
  std::unique_ptr<uhaptics::JointIo> inner_;
  std::vector<double> positions_;
  std::uint32_t time_us_ = 0;
};

// A device that costs nothing, with a uhaptics device's specification and position: CHAI3D's tick
// alone, on the same scene scale and stiffness as with that device.
class cStillDevice : public cGenericHapticDevice {
 public:
  cStillDevice(const cHapticDeviceInfo& a_specifications, const cVector3d& a_position, const cMatrix3d& a_rotation)
      : m_position(a_position), m_rotation(a_rotation) {
    m_specifications = a_specifications;
    m_specifications.m_modelName = "still " + a_specifications.m_modelName;
    m_deviceAvailable = true;
  }
  bool open() override { return m_deviceReady = true; }
  bool close() override { return !(m_deviceReady = false); }
  bool calibrate(bool) override { return true; }
  bool getPosition(cVector3d& a_position) override {
    a_position = m_position;
    return true;
  }
  bool getRotation(cMatrix3d& a_rotation) override {
    a_rotation = m_rotation;
    return true;
  }
  bool setForceAndTorqueAndGripperForce(const cVector3d& a_force, const cVector3d& a_torque, double) override {
    m_prevForce = a_force;
    m_prevTorque = a_torque;
    return true;
  }

 private:
  cVector3d m_position;
  cMatrix3d m_rotation;
};

// A world as CHAI3D's examples build it: workspace radius 1, a 0.3 sphere mesh of 64 x 64 facets
// with an AABB tree, stiffness half the device's maximum.
struct Scene {
  static constexpr double kSphereRadius = 0.3;
  static constexpr double kToolRadius = 0.01;

  explicit Scene(const cGenericHapticDevicePtr& device, bool contact) {
    world = new cWorld();
    tool = new cToolCursor(world);
    world->addChild(tool);
    tool->setHapticDevice(device);
    tool->setWorkspaceRadius(1.0);
    tool->setRadius(kToolRadius);
    tool->start();
    mesh = new cMesh();
    cCreateSphere(mesh, kSphereRadius, 64, 64);
    world->addChild(mesh);
    const double scale = tool->getWorkspaceScaleFactor();
    mesh->m_material->setStiffness(0.5 * device->getSpecifications().m_maxLinearStiffness / scale);
    mesh->createAABBCollisionDetector(kToolRadius);
    // Where the device holds the tool; the sphere's equator goes 1 mm (device) past it along y, in
    // the plane of the planar devices (and away from the pole, where the 64 slices meet and a contact
    // costs CHAI3D ten times more), or the sphere stays far away.
    const cVector3d far(0.0, 0.0, 100.0 * kSphereRadius);
    mesh->setLocalPos(far);
    tick();
    const cVector3d at = tool->getDeviceGlobalPos();
    if (contact) {
      // The finger proxy meets a surface only on its way to the device's position: the tool is
      // moved clear (its own offset; the device stays where it is), the sphere placed, and the tool
      // brought onto it.
      const double depth = 1e-3 * scale;
      tool->setLocalPos(0.0, 2.0 * depth, 0.0);
      tick();
      mesh->setLocalPos(at - cVector3d(0.0, kSphereRadius - depth, 0.0));
      for (int i = 20; i >= 0; --i) {
        tool->setLocalPos(0.0, 2.0 * depth * i / 20.0, 0.0);
        tick();
      }
    }
  }
  ~Scene() {
    tool->stop();
    delete world;  // deletes its children
  }
  // One iteration of CHAI3D's examples' haptic loop.
  void tick() {
    world->computeGlobalPositions(true);
    tool->updateFromDevice();
    tool->computeInteractionForces();
    tool->applyToDevice();
  }
  cWorld* world;
  cToolCursor* tool;
  cMesh* mesh;
};

void runScene(benchmark::State& state, const cGenericHapticDevicePtr& device, bool contact) {
  Scene scene(device, contact);
  for (int i = 0; i < 200; ++i) scene.tick();  // the proxy settles, buffers reach their size
  if (contact && scene.tool->getDeviceGlobalForce().length() <= 0.0) {
    state.SkipWithError("the tool is not in contact with the sphere");
    return;
  }
  uhaptics::tools::AllocationScope allocations;
  for (auto _ : state) scene.tick();
  state.counters["allocs_per_tick"] =
      benchmark::Counter(static_cast<double>(allocations.count()), benchmark::Counter::kAvgIterations);
  state.counters["force_N"] = scene.tool->getDeviceGlobalForce().length();
}

uhaptics::DeviceSelection heldStill(const std::string& name) {
  uhaptics::DeviceSelection selection;
  selection.device = name;
  selection.hand_enabled = false;
  selection.options["referee"] = 0.0;  // a board's path: nothing judges the plant's truth
  selection.wrap_joint_io = [](std::unique_ptr<uhaptics::JointIo> io) -> std::unique_ptr<uhaptics::JointIo> {
    return std::make_unique<HeldStillJointIo>(std::move(io));
  };
  return selection;
}

// CHAI3D's tick on a still device with `name`'s specification, where `name` holds the tool.
void chai3dTick(benchmark::State& state, const std::string& name, bool contact) {
  chai3d::cUhapticsDevicePtr device = uhaptics::adapter::createDevice(heldStill(name));
  cVector3d position;
  cMatrix3d rotation;
  if (!device->open() || !device->getPosition(position) || !device->getRotation(rotation)) {
    state.SkipWithError(("device '" + name + "' does not open").c_str());
    return;
  }
  const cHapticDeviceInfo specifications = device->getSpecifications();
  device->close();
  cGenericHapticDevicePtr still = std::make_shared<cStillDevice>(specifications, position, rotation);
  runScene(state, still, contact);
}

// The same tick with the device behind the tool, through CHAI3D's handler and the slot.
void deviceTick(benchmark::State& state, const std::string& name, bool contact) {
  uhaptics::adapter::selectSlotDevice(heldStill(name));
  {
    auto handler = std::make_unique<cHapticDeviceHandler>();
    cGenericHapticDevicePtr device;
    if (!handler->getDevice(device, 0) || !device) {
      state.SkipWithError(("CHAI3D's handler has no device for '" + name + "'").c_str());
    } else {
      uhaptics::adapter::uhapticsDevice(device)->setLockStep(true);
      runScene(state, device, contact);
    }
  }
  uhaptics::adapter::resetSlotSelection();
}

}  // namespace

namespace uhaptics::bench {

void registerChai3dTickBenchmarks() {
  // BM_Chai3dTick/<device>/<contact|free>/<chai3d|uhaptics>: CHAI3D alone, then with the device.
  for (const std::string& name : adapter::deviceNames()) {
    for (const bool contact : {true, false}) {
      const std::string prefix = "BM_Chai3dTick/" + name + (contact ? "/contact" : "/free");
      benchmark::RegisterBenchmark((prefix + "/chai3d").c_str(),
                                   [name, contact](benchmark::State& s) { chai3dTick(s, name, contact); });
      benchmark::RegisterBenchmark((prefix + "/uhaptics").c_str(),
                                   [name, contact](benchmark::State& s) { deviceTick(s, name, contact); });
    }
  }
}

}  // namespace uhaptics::bench
