#pragma once
// The one interface every renderer sees of a device: its kinematics, with sizes fixed at compile
// time. A device model M satisfies KinematicModel when it provides
//
//   static constexpr int kJoints;    // dim q (actuated + sensed-only joints)
//   static constexpr int kActuated;  // dim of the actuated subset (= kJoints on fully actuated devices)
//   static constexpr int kTask;      // dim x of the probe / end effector the renderer controls
//   using JointVector = Vec<kJoints>;  using TaskVector = Vec<kTask>;
//   using Jacobian = Mat<kTask, kJoints>;  using Selection = Mat<kActuated, kJoints>;
//   void forward(const JointVector& q, TaskVector& x) const noexcept;     // x = f(q)
//   void jacobian(const JointVector& q, Jacobian& J) const noexcept;      // J = df/dq
//   const Selection& selection() const noexcept;                          // q_a = S q
//
// forward() and jacobian() are const and allocation-free, so a renderer may call them repeatedly
// within one tick (iterative solves). A model whose forward map is only defined implicitly (a
// parallel mechanism's forward kinematics) still exposes this interface, with its own tolerance.
#include <type_traits>
#include <utility>

#include "uhaptics/core/types.hpp"

namespace uhaptics {

template <typename M, typename = void>
struct IsKinematicModel : std::false_type {};

template <typename M>
struct IsKinematicModel<
    M, std::void_t<decltype(M::kJoints), decltype(M::kActuated), decltype(M::kTask),
                   decltype(std::declval<const M&>().forward(std::declval<const Vec<M::kJoints>&>(),
                                                             std::declval<Vec<M::kTask>&>())),
                   decltype(std::declval<const M&>().jacobian(std::declval<const Vec<M::kJoints>&>(),
                                                              std::declval<Mat<M::kTask, M::kJoints>&>())),
                   decltype(std::declval<const M&>().selection())>> : std::true_type {};

template <typename M>
inline constexpr bool kIsKinematicModel = IsKinematicModel<M>::value;

/// Optional capability: a closed-form inverse  bool inverse(const TaskVector& x, JointVector& q) const
/// (true when x is reachable). Solvers use it to seed an iteration that a poor start cannot finish.
template <typename M, typename = void>
struct HasInverseKinematics : std::false_type {};

template <typename M>
struct HasInverseKinematics<
    M, std::void_t<decltype(bool{std::declval<const M&>().inverse(std::declval<const Vec<M::kTask>&>(),
                                                                 std::declval<Vec<M::kJoints>&>())})>>
    : std::true_type {};

template <typename M>
inline constexpr bool kHasInverseKinematics = HasInverseKinematics<M>::value;

}  // namespace uhaptics
