#pragma once
// Switching between the free-motion and the stiff-contact desired FME (paper 003, eq. 15-19):
// M_des = Omega M_free + (1 - Omega) M_stiff, with the activation Omega driven by the saturation
// observer V through two thresholds (hysteresis: enter stiff when V < eps1, leave when V >= eps2)
// and moved with a half-cosine over t_f - t_0 = rho |M_free - M_stiff|_F (eq. 19).
//
// The paper's eq. 17/18 start each blend from 0 or 1. A reversal while a blend is still running
// starts from the current Omega instead and scales the duration by the distance left, which keeps
// Omega continuous in every case and reduces to eq. 17/18 otherwise.
#include <algorithm>
#include <cmath>

namespace uhaptics {

struct EllipsoidTransitionOptions {
  double enter_stiff_below = 0.7;  // eps1
  double leave_stiff_at = 0.95;    // eps2 (>= eps1)
  double rho = 0.003;              // s per unit of |M_free - M_stiff|_F
  bool smooth = true;              // false: Omega jumps (the paper's case without the transition)
  bool valid() const noexcept {
    return enter_stiff_below >= 0.0 && enter_stiff_below <= 1.0 && leave_stiff_at >= enter_stiff_below &&
           leave_stiff_at <= 1.0 && rho >= 0.0 && std::isfinite(rho);
  }
};

class EllipsoidTransition {
 public:
  /// Omega = 1 (free-motion ellipsoid), nothing in progress.
  void reset(double omega = 1.0) noexcept {
    omega_ = from_ = target_ = std::clamp(omega, 0.0, 1.0);
    duration_ = 0.0;
  }

  /// Advances to time t with observer value V; distance = |M_free - M_stiff|_F. Returns Omega.
  double update(double t, double V, double distance, const EllipsoidTransitionOptions& opt) noexcept {
    if (target_ == 1.0 && V < opt.enter_stiff_below) start(0.0, t, distance, opt);
    else if (target_ == 0.0 && V >= opt.leave_stiff_at) start(1.0, t, distance, opt);
    if (omega_ != target_) {
      const double s = duration_ > 0.0 ? (t - t0_) / duration_ : 1.0;
      if (!(s < 1.0)) omega_ = target_;
      else omega_ = from_ + (target_ - from_) * 0.5 * (1.0 - std::cos(M_PI * std::max(s, 0.0)));
    }
    return omega_;
  }

  double omega() const noexcept { return omega_; }
  double target() const noexcept { return target_; }
  /// True when Omega is settled at the free-motion ellipsoid.
  bool settledFree() const noexcept { return omega_ == 1.0 && target_ == 1.0; }
  bool inProgress() const noexcept { return omega_ != target_; }

 private:
  void start(double target, double t, double distance, const EllipsoidTransitionOptions& opt) noexcept {
    from_ = omega_;
    target_ = target;
    t0_ = t;
    duration_ = opt.smooth ? opt.rho * distance * std::abs(target - from_) : 0.0;
  }

  double omega_ = 1.0, from_ = 1.0, target_ = 1.0;
  double t0_ = 0.0, duration_ = 0.0;
};

}  // namespace uhaptics
