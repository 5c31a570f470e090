#pragma once
// Optional capabilities a kinematic model (kinematic_model.hpp) may offer beyond the common
// interface. Renderers use them when present and fall back otherwise:
//
//   void jacobianDerivative(const JointVector& q, int k, Jacobian& dJ) const noexcept;  // dJ/dq_k
//   void jacobianDerivatives(const JointVector& q, std::array<Jacobian, kJoints>& dJ) const noexcept;
//                                   // every dJ/dq_k at once (shares the work the single ones repeat)
//   void jacobian(const JointVector& q, const TaskVector& x, Jacobian& J) const noexcept; // J at q,
//                                   // given x = forward(q) (for a model whose J needs f(q) first)
//   void massMatrix(const JointVector& q, Mat<kJoints, kJoints>& M) const noexcept;   // joint space
//   const JointLimits<kJoints>& jointLimits() const noexcept;                          // mechanical limits
//   bool inWorkingRange(const JointVector& q) const noexcept;                         // q is a real state
//
// Without jacobianDerivative a renderer differentiates jacobian() numerically; without massMatrix
// it uses the kinematic (identity-metric) null space; without jointLimits it assumes none; without
// inWorkingRange every finite q counts as a real state (models whose forward() continues outside
// the assembly region, like the exoskeleton's, must offer it so that renderers refuse such states
// instead of rendering from a fictitious configuration).
#include <array>
#include <type_traits>
#include <utility>

#include "uhaptics/core/joint_limits.hpp"
#include "uhaptics/core/kinematic_model.hpp"

namespace uhaptics {

template <typename M, typename = void>
struct HasJacobianDerivative : std::false_type {};
template <typename M>
struct HasJacobianDerivative<M, std::void_t<decltype(std::declval<const M&>().jacobianDerivative(
                                    std::declval<const Vec<M::kJoints>&>(), 0,
                                    std::declval<Mat<M::kTask, M::kJoints>&>()))>> : std::true_type {};
template <typename M>
inline constexpr bool kHasJacobianDerivative = HasJacobianDerivative<M>::value;

template <typename M, typename = void>
struct HasJacobianDerivatives : std::false_type {};
template <typename M>
struct HasJacobianDerivatives<M, std::void_t<decltype(std::declval<const M&>().jacobianDerivatives(
                                     std::declval<const Vec<M::kJoints>&>(),
                                     std::declval<std::array<Mat<M::kTask, M::kJoints>, M::kJoints>&>()))>>
    : std::true_type {};
template <typename M>
inline constexpr bool kHasJacobianDerivatives = HasJacobianDerivatives<M>::value;

template <typename M, typename = void>
struct HasJacobianFromForward : std::false_type {};
template <typename M>
struct HasJacobianFromForward<M, std::void_t<decltype(std::declval<const M&>().jacobian(
                                     std::declval<const Vec<M::kJoints>&>(), std::declval<const Vec<M::kTask>&>(),
                                     std::declval<Mat<M::kTask, M::kJoints>&>()))>> : std::true_type {};
template <typename M>
inline constexpr bool kHasJacobianFromForward = HasJacobianFromForward<M>::value;

template <typename M, typename = void>
struct HasMassMatrix : std::false_type {};
template <typename M>
struct HasMassMatrix<M, std::void_t<decltype(std::declval<const M&>().massMatrix(
                            std::declval<const Vec<M::kJoints>&>(), std::declval<Mat<M::kJoints, M::kJoints>&>()))>>
    : std::true_type {};
template <typename M>
inline constexpr bool kHasMassMatrix = HasMassMatrix<M>::value;

template <typename M, typename = void>
struct HasJointLimits : std::false_type {};
template <typename M>
struct HasJointLimits<M, std::enable_if_t<std::is_convertible_v<decltype(std::declval<const M&>().jointLimits()),
                                                                const JointLimits<M::kJoints>&>>> : std::true_type {};
template <typename M>
inline constexpr bool kHasJointLimits = HasJointLimits<M>::value;

template <typename M, typename = void>
struct HasWorkingRange : std::false_type {};
template <typename M>
struct HasWorkingRange<M, std::enable_if_t<std::is_same_v<
                              decltype(std::declval<const M&>().inWorkingRange(std::declval<const Vec<M::kJoints>&>())),
                              bool>>> : std::true_type {};
template <typename M>
inline constexpr bool kHasWorkingRange = HasWorkingRange<M>::value;

}  // namespace uhaptics
