#include "uhaptics/renderers/tau_wall_front_end.hpp"

#include <cmath>

namespace uhaptics {

TauServoFrontEnd::TauServoFrontEnd(const TauModel& model) : model_(model), data_(model) {}

void TauServoFrontEnd::reset() noexcept {
  has_previous_ = false;
  qd_.setZero();
  data_.pose = model_.homePose();
}

Fault TauServoFrontEnd::update(const Vec6& q, const SurfaceContact& contact, const Vec6* pose) noexcept {
  if (!q.allFinite()) return Fault::kNonFiniteInput;
  if (contact.active && (!contact.point.allFinite() || !contact.normal.allFinite() ||
                         std::abs(contact.normal.norm() - 1.0) > 1e-6))
    return Fault::kNonFiniteInput;
  qd_ = has_previous_ ? ((q - q_) / model_.servoPeriod()).eval() : Vec6::Zero().eval();
  q_ = q;
  has_previous_ = true;
  if (pose) {
    if (!pose->allFinite()) return Fault::kNonFiniteInput;
    data_.pose = *pose;
  }
  // With a caller-supplied pose Newton starts at the solution and only evaluates J (0 iterations).
  const Fault f = model_.forward(q, data_);
  if (f != Fault::kNone) return f;
  model_.computeGravity(q, data_);
  return Fault::kNone;
}

}  // namespace uhaptics
