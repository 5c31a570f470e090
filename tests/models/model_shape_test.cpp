// The one shape every device model follows (docs/adding-a-device.md, "The model"), checked at
// compile time: loading, home configuration, limits, kinematics and the Data made from the model.
#include <catch2/catch.hpp>
#include <string>
#include <type_traits>
#include <utility>

#include "uhaptics/core/model_capabilities.hpp"
#include "uhaptics/models/exo_finger_model.hpp"
#include "uhaptics/models/param_file.hpp"
#include "uhaptics/models/planar_linkage_model.hpp"
#include "uhaptics/models/tau_model.hpp"

using namespace uhaptics;

namespace {

// load(path[, device]) and fromParams(params[, device]) return the model; Device... is the device
// name argument of a class that serves several devices.
template <typename M, typename... Device>
constexpr bool kLoads =
    std::is_same_v<decltype(M::load(std::declval<const std::string&>(), std::declval<Device>()...)), M> &&
    std::is_same_v<decltype(M::fromParams(std::declval<const ParamFile&>(), std::declval<Device>()...)), M>;

// homeJoints() in joint space.
template <typename M>
constexpr bool kHomes = std::is_same_v<decltype(std::declval<const M&>().homeJoints()), const typename M::JointVector&>;

// effortLimits() one per actuator.
template <typename M>
constexpr bool kEffortLimits =
    std::is_same_v<decltype(std::declval<const M&>().effortLimits()), const Vec<M::kActuated>&>;

// model.forward(q, data) fills the Data.
template <typename M, typename D, typename = void>
struct FillsData : std::false_type {};
template <typename M, typename D>
struct FillsData<M, D,
                 std::void_t<decltype(std::declval<const M&>().forward(std::declval<const typename M::JointVector&>(),
                                                                       std::declval<D&>()))>> : std::true_type {};

// The Data is made from the model only (no default, no implicit conversion) and filled by it.
template <typename M, typename D>
constexpr bool kDataFromModel = std::is_constructible_v<D, const M&> && !std::is_convertible_v<const M&, D> &&
                                !std::is_default_constructible_v<D> && FillsData<M, D>::value;

}  // namespace

TEST_CASE("model shape: every device model has the same loading, home, limits, kinematics and Data", "[models]") {
  STATIC_REQUIRE(kLoads<TauModel>);
  STATIC_REQUIRE(kLoads<ExoFingerModel>);
  STATIC_REQUIRE(kLoads<Rhi4Model, const std::string&>);
  STATIC_REQUIRE(kLoads<Planar3Model, const std::string&>);

  // A home configuration where the device has one (the exoskeleton follows the finger it is worn on).
  STATIC_REQUIRE(kHomes<TauModel>);
  STATIC_REQUIRE(kHomes<Rhi4Model>);
  STATIC_REQUIRE(kHomes<Planar3Model>);
  STATIC_REQUIRE(std::is_same_v<decltype(std::declval<const TauModel&>().homePose()), const TauModel::TaskVector&>);

  STATIC_REQUIRE(kEffortLimits<TauModel>);
  STATIC_REQUIRE(kEffortLimits<ExoFingerModel>);
  STATIC_REQUIRE(kEffortLimits<Rhi4Model>);
  STATIC_REQUIRE(kEffortLimits<Planar3Model>);

  // Mechanical joint ranges where the device has them (the TAU's file gives none).
  STATIC_REQUIRE(kHasJointLimits<ExoFingerModel>);
  STATIC_REQUIRE(kHasJointLimits<Rhi4Model>);
  STATIC_REQUIRE(kHasJointLimits<Planar3Model>);

  STATIC_REQUIRE(kIsKinematicModel<TauModel>);
  STATIC_REQUIRE(kIsKinematicModel<ExoFingerModel>);
  STATIC_REQUIRE(kIsKinematicModel<Rhi4Model>);
  STATIC_REQUIRE(kIsKinematicModel<Planar3Model>);

  STATIC_REQUIRE(kDataFromModel<TauModel, TauData>);
  STATIC_REQUIRE(kDataFromModel<ExoFingerModel, ExoFingerData>);
}
