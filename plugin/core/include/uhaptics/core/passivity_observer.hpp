#pragma once
// Energy observer at a device's mechanical port (Hannaford & Ryu, 2002), for sampled control.
//
// A command u_k held over one period (zero-order hold) while the joints move from q_k to q_{k+1}
// delivers exactly W_k = u_k . (q_{k+1} - q_k) of work to the mechanism, whatever happens inside the
// period. The observer sums that work; energy the renderer *generated* is the part of the output that
// was not first put in by the user:
//
//   E_out(n) = sum_k W_k        (work done by the actuators on the user's hand)
//
// A passive renderer keeps E_out(n) <= E_stored(n) (energy it holds, e.g. a compressed virtual
// spring) at every n, so with a renderer that releases all of it at the end, E_out <= 0 up to the
// sensor resolution. allocation-free, O(dim) per update.
#include <Eigen/Core>
#include <algorithm>
#include <limits>

namespace uhaptics {

template <int N>
class PassivityObserver {
 public:
  using Vector = Eigen::Matrix<double, N, 1>;

  explicit PassivityObserver(Eigen::Index dim = N > 0 ? N : 0) : last_q_(Vector::Zero(dim)) {}

  void reset() noexcept {
    energy_out_ = 0.0;
    peak_ = -std::numeric_limits<double>::infinity();
    started_ = false;
  }

  /// Records the joint position q measured at the start of the period and the command u applied
  /// over it (the next call's q closes that period).
  template <typename DQ, typename DU>
  void update(const Eigen::MatrixBase<DQ>& q, const Eigen::MatrixBase<DU>& u) noexcept {
    if (started_) {
      energy_out_ += last_u_.dot(q - last_q_);
      peak_ = std::max(peak_, energy_out_);
    }
    last_q_ = q;
    last_u_ = u;
    started_ = true;
  }

  /// Net work done on the user so far [J] (positive: the device gave energy).
  double energyOut() const noexcept { return energy_out_; }
  /// Largest value energyOut() reached.
  double peakEnergyOut() const noexcept { return started_ ? peak_ : 0.0; }

 private:
  Vector last_q_;
  Vector last_u_ = Vector::Zero(N > 0 ? N : 0);
  double energy_out_ = 0.0;
  double peak_ = -std::numeric_limits<double>::infinity();
  bool started_ = false;
};

}  // namespace uhaptics
