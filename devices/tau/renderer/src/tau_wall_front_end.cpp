#include "uhaptics/renderers/tau_wall_front_end.hpp"

#include <cmath>

namespace uhaptics {

TauServoFrontEnd::TauServoFrontEnd(const TauModel& model) : model_(model), data_(model) {}

void TauServoFrontEnd::reset() noexcept {
  has_previous_ = false;
  data_current_ = false;
  qd_.setZero();
  data_.pose = model_.homePose();
}

bool TauServoFrontEnd::acceptInputs(const Vec6& q, const SurfaceContact& contact, bool& same_q) noexcept {
  same_q = false;
  if (!q.allFinite()) return false;
  if (contact.active && (!contact.point.allFinite() || !contact.normal.allFinite() ||
                         std::abs(contact.normal.norm() - 1.0) > 1e-6))
    return false;
  qd_ = has_previous_ ? ((q - q_) / model_.servoPeriod()).eval() : Vec6::Zero().eval();
  same_q = has_previous_ && q == q_;
  q_ = q;
  has_previous_ = true;
  return true;
}

Fault TauServoFrontEnd::update(const Vec6& q, const SurfaceContact& contact, const TauData& solved) noexcept {
  bool same_q = false;
  data_current_ = false;
  if (!acceptInputs(q, contact, same_q)) return Fault::kNonFiniteInput;
  if (!solved.pose.allFinite()) return Fault::kNonFiniteInput;
  // What forward(q) started at this pose would give: the same pose and Jacobian (0 iterations).
  data_.pose = solved.pose;
  data_.J = solved.J;
  if (!data_.J.allFinite()) return Fault::kSingular;
  model_.computeGravity(q, data_);
  data_current_ = true;
  return Fault::kNone;
}

Fault TauServoFrontEnd::update(const Vec6& q, const SurfaceContact& contact, const Vec6* pose) noexcept {
  bool same_q = false;
  const Vec6 q_solved = q_;  // where data_ was solved, if data_current_
  if (!acceptInputs(q, contact, same_q)) {
    data_current_ = false;
    return Fault::kNonFiniteInput;
  }
  if (pose) {
    if (!pose->allFinite()) {
      data_current_ = false;
      return Fault::kNonFiniteInput;
    }
    if (same_q && data_current_ && *pose == data_.pose) return Fault::kNone;
    data_.pose = *pose;
  } else if (same_q && data_current_) {
    return Fault::kNone;  // Newton would start at the solution for q and stop there
  } else if (data_current_) {
    // Newton from the first-order prediction X + J dq: one iteration where the last solution would
    // take two or three after an encoder count's step.
    data_.pose.noalias() += data_.J * (q - q_solved);
  }
  // With a caller-supplied pose Newton starts at the solution and only evaluates J (0 iterations).
  data_current_ = false;
  const Fault f = model_.forward(q, data_);
  if (f != Fault::kNone) return f;
  model_.computeGravity(q, data_);
  data_current_ = true;
  return Fault::kNone;
}

}  // namespace uhaptics
