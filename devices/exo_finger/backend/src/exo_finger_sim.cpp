#include "uhaptics/backends/exo_finger_sim.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include "uhaptics/core/finite_difference.hpp"
#include "uhaptics/core/regularized_solve.hpp"

namespace uhaptics {

namespace {
constexpr double kPi = 3.14159265358979323846;
double raisedCosine(double t, double period) { return 0.5 * (1.0 - std::cos(2.0 * kPi * t / period)); }
}  // namespace

FingerTrajectory FingerTrajectory::synthesized(const ExoFingerModel& model, double duration_s, double period_s,
                                               double sample_rate_hz, double margin) {
  if (!(duration_s > 0.0 && duration_s < 3600.0)) throw Error("trajectory duration must lie in (0, 3600) s");
  if (!(period_s > 0.05 && period_s < 600.0)) throw Error("trajectory period must lie in (0.05, 600) s");
  if (!(sample_rate_hz >= 10.0 && sample_rate_hz <= 1e5)) throw Error("trajectory rate must lie in [10, 1e5] Hz");
  if (!(margin >= 0.0 && margin < 0.5)) throw Error("trajectory margin must lie in [0, 0.5)");
  const ExoFingerModel::TaskVector lo = model.taskLower(), span = model.taskUpper() - model.taskLower();
  const auto n = static_cast<std::size_t>(std::ceil(duration_s * sample_rate_hz)) + 1;
  std::vector<double> t(n);
  std::vector<ExoFingerModel::TaskVector> x(n);
  for (std::size_t i = 0; i < n; ++i) {
    t[i] = static_cast<double>(i) / sample_rate_hz;
    const double mcp = raisedCosine(t[i], period_s);
    const double pip = raisedCosine(t[i], period_s * 2.0 / 3.0);
    x[i] = lo + span.cwiseProduct(ExoFingerModel::TaskVector(margin + (1.0 - 2.0 * margin) * mcp,
                                                              margin + (1.0 - 2.0 * margin) * pip));
  }
  return fromSamples(model, std::move(t), std::move(x), "synthesized trajectory");
}

namespace {

Vec2 fingertipOf(const ExoFingerModel& model, const ExoFingerModel::TaskVector& x) {
  ExoFingerPoints points;
  model.points(x, points);
  return points.fingertip;
}

// The finger angles in [lo, hi] whose fingertip is nearest target, from start: Gauss-Newton with
// an active set on the box (an angle held at a bound the step pushes against drops out and the
// other one is solved alone), so an unreachable target ends at the nearest point of the edge.
ExoFingerModel::TaskVector nearestAngles(const ExoFingerModel& model, const Vec2& target,
                                         const ExoFingerModel::TaskVector& lo, const ExoFingerModel::TaskVector& hi,
                                         ExoFingerModel::TaskVector x) {
  const auto tip = [&](const ExoFingerModel::TaskVector& y) { return fingertipOf(model, y); };
  for (int iteration = 0; iteration < 50; ++iteration) {
    const Vec2 error = target - tip(x);
    const Mat2 J = centralDifferenceJacobian(tip, x);
    bool free[2] = {true, true};
    Vec2 step = Vec2::Zero();
    for (int pass = 0; pass < 3; ++pass) {
      Mat2 Jf = J;
      for (int i = 0; i < 2; ++i)
        if (!free[i]) Jf.col(i).setZero();
      // Damped least squares: defined at a stretched finger and for a dropped column.
      step = (Jf.transpose() * Jf + 1e-12 * Mat2::Identity()).ldlt().solve(Jf.transpose() * error);
      bool changed = false;
      for (int i = 0; i < 2; ++i) {
        const bool pushes_out = (x(i) <= lo(i) && step(i) < 0.0) || (x(i) >= hi(i) && step(i) > 0.0);
        if (free[i] && pushes_out) {
          free[i] = false;
          changed = true;
        }
      }
      if (!changed) break;
    }
    // Backtracking: far from the finger's reach the residual is large and a full Gauss-Newton step
    // can overshoot into another basin; only a step that brings the fingertip closer is taken.
    const double distance = error.norm();
    ExoFingerModel::TaskVector next = x;
    for (double scale = 1.0; scale > 1e-4; scale *= 0.5) {
      const ExoFingerModel::TaskVector trial = (x + scale * step).cwiseMax(lo).cwiseMin(hi);
      if ((target - tip(trial)).norm() < distance) {
        next = trial;
        break;
      }
    }
    const bool settled = (next - x).norm() < 1e-10;
    x = next;
    if (settled) break;
  }
  return x;
}

}  // namespace

FingerTrajectory FingerTrajectory::followingPath(const ExoFingerModel& model,
                                                 const std::function<Vec2(double)>& fingertip_target,
                                                 double period_s, double duration_s, double sample_rate_hz) {
  if (!(duration_s > 0.0 && duration_s < 3600.0)) throw Error("trajectory duration must lie in (0, 3600) s");
  if (!(period_s > 0.05 && period_s < 600.0)) throw Error("trajectory period must lie in (0.05, 600) s");
  if (!(sample_rate_hz >= 10.0 && sample_rate_hz <= 1e5)) throw Error("trajectory rate must lie in [10, 1e5] Hz");
  // The same 5 % margin off the joint ranges as the synthesized cycles.
  const ExoFingerModel::TaskVector full = model.taskUpper() - model.taskLower();
  const ExoFingerModel::TaskVector lo = model.taskLower() + 0.05 * full, span = 0.9 * full;
  const auto per_period = static_cast<std::size_t>(std::ceil(period_s * sample_rate_hz));
  std::vector<ExoFingerModel::TaskVector> period(per_period);
  for (std::size_t i = 0; i < per_period; ++i) {
    const Vec2 target = fingertip_target(period_s * static_cast<double>(i) / static_cast<double>(per_period));
    if (!target.allFinite()) throw Error("fingertip path is not finite at sample " + std::to_string(i));
    ExoFingerModel::TaskVector start = i > 0 ? period[i - 1] : lo + 0.5 * span;
    if (i == 0) {  // the nearest point of an 11 x 11 grid: away from a local minimum of the far side
      double best = (fingertipOf(model, start) - target).norm();
      for (int a = 0; a <= 10; ++a) {
        for (int b = 0; b <= 10; ++b) {
          const ExoFingerModel::TaskVector x = lo + span.cwiseProduct(ExoFingerModel::TaskVector(0.1 * a, 0.1 * b));
          const double distance = (fingertipOf(model, x) - target).norm();
          if (distance < best) {
            best = distance;
            start = x;
          }
        }
      }
    }
    period[i] = nearestAngles(model, target, lo, lo + span, start);
  }
  const auto n = static_cast<std::size_t>(std::ceil(duration_s * sample_rate_hz)) + 1;
  std::vector<double> t(n);
  std::vector<ExoFingerModel::TaskVector> x(n);
  for (std::size_t i = 0; i < n; ++i) {
    t[i] = static_cast<double>(i) * period_s / static_cast<double>(per_period);
    x[i] = period[i % per_period];
  }
  return fromSamples(model, std::move(t), std::move(x), "fingertip path");
}

FingerTrajectory FingerTrajectory::synthesizedAround(const ExoFingerModel& model,
                                                    const ExoFingerModel::TaskVector& centre, double amplitude,
                                                    double duration_s, double period_s, double sample_rate_hz) {
  if (!(duration_s > 0.0 && duration_s < 3600.0)) throw Error("trajectory duration must lie in (0, 3600) s");
  if (!(period_s > 0.05 && period_s < 600.0)) throw Error("trajectory period must lie in (0.05, 600) s");
  if (!(sample_rate_hz >= 10.0 && sample_rate_hz <= 1e5)) throw Error("trajectory rate must lie in [10, 1e5] Hz");
  if (!(amplitude >= 0.0 && amplitude < 1.0)) throw Error("trajectory amplitude must lie in [0, 1) rad");
  const auto n = static_cast<std::size_t>(std::ceil(duration_s * sample_rate_hz)) + 1;
  std::vector<double> t(n);
  std::vector<ExoFingerModel::TaskVector> x(n);
  const double w = 2.0 * kPi / period_s;
  for (std::size_t i = 0; i < n; ++i) {
    t[i] = static_cast<double>(i) / sample_rate_hz;
    x[i] = centre + amplitude * ExoFingerModel::TaskVector(std::sin(w * t[i]), std::sin(1.5 * w * t[i] + 1.0));
  }
  // fromSamples names the first pose outside the working range if centre +- amplitude leaves it.
  return fromSamples(model, std::move(t), std::move(x), "synthesized trajectory around a pose");
}

FingerTrajectory FingerTrajectory::fromCsv(const ExoFingerModel& model, const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error(path + ": cannot open trajectory file");
  std::string line;
  if (!std::getline(in, line)) throw Error(path + ": empty trajectory file");
  if (line.rfind("time_s,mcp_rad,pip_rad", 0) != 0)
    throw Error(path + ": header must start with 'time_s,mcp_rad,pip_rad', found '" + line + "'");
  std::vector<double> t;
  std::vector<ExoFingerModel::TaskVector> x;
  int line_no = 1;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.empty()) continue;
    std::stringstream row(line);
    double v[3];
    for (double& value : v) {
      std::string cell;
      if (!std::getline(row, cell, ',')) throw Error(path + ":" + std::to_string(line_no) + ": expected 3 numbers");
      try {
        std::size_t used = 0;
        value = std::stod(cell, &used);
        if (cell.find_first_not_of(" \t\r", used) != std::string::npos) throw std::invalid_argument(cell);
      } catch (const std::exception&) {
        throw Error(path + ":" + std::to_string(line_no) + ": '" + cell + "' is not a number");
      }
    }
    t.push_back(v[0]);
    x.emplace_back(v[1], v[2]);
  }
  return fromSamples(model, std::move(t), std::move(x), path);
}

FingerTrajectory FingerTrajectory::fromSamples(const ExoFingerModel& model, std::vector<double> time_s,
                                               std::vector<ExoFingerModel::TaskVector> x, const std::string& origin) {
  if (time_s.size() < 2 || time_s.size() != x.size())
    throw Error(origin + ": a trajectory needs at least 2 samples with one pose each");
  for (std::size_t i = 0; i < time_s.size(); ++i) {
    const std::string where = origin + ": sample " + std::to_string(i);
    if (!std::isfinite(time_s[i]) || !x[i].allFinite()) throw Error(where + " is not finite");
    if (i > 0 && !(time_s[i] > time_s[i - 1])) throw Error(where + ": times must increase strictly");
    if (!model.taskInRange(x[i], 1e-9)) {
      std::ostringstream msg;
      msg << where << ": pose (" << x[i](0) << ", " << x[i](1) << ") rad is outside the working range [" << model.taskLower()(0)
          << ", " << model.taskUpper()(0) << "] x [" << model.taskLower()(1) << ", " << model.taskUpper()(1) << "]";
      throw Error(msg.str());
    }
  }
  FingerTrajectory traj;
  traj.time_ = std::move(time_s);
  traj.x_ = std::move(x);
  return traj;
}

ExoFingerModel::TaskVector FingerTrajectory::at(double t) const noexcept {
  if (t <= time_.front()) return x_.front();
  if (t >= time_.back()) return x_.back();
  const auto it = std::upper_bound(time_.begin(), time_.end(), t);
  const std::size_t i = static_cast<std::size_t>(it - time_.begin());
  const double s = (t - time_[i - 1]) / (time_[i] - time_[i - 1]);
  return (1.0 - s) * x_[i - 1] + s * x_[i];
}

ExoFingerSim::ExoFingerSim(const ExoFingerModel& model, FingerTrajectory trajectory, const ExoFingerSimOptions& options)
    : model_(model), trajectory_(std::move(trajectory)), options_(options) {
  if (!(options.update_rate_hz >= 10.0 && options.update_rate_hz <= 1e5))
    throw Error("exo simulator: update_rate_hz must lie in [10, 100000]");
  if (trajectory_.samples() < 2) throw Error("exo simulator: empty trajectory");
  period_ = 1.0 / options.update_rate_hz;
  state_.time = trajectory_.startTime();
  sense();
}

void ExoFingerSim::command(const ExoFingerModel::ActuatorVector& force) noexcept {
  if (!force.allFinite()) {
    commanded_ = 0.0;
    state_.fault = Fault::kNonFiniteInput;
    return;
  }
  state_.fault = Fault::kNone;
  const double limit = model_.effortLimits()(0);
  commanded_ = std::clamp(force(0), -limit, limit);
}

void ExoFingerSim::step() noexcept {
  // Board force loop: exact discretization of a first-order lag over one period.
  const double tau = model_.forceLoopTimeConstant();
  const double alpha = (options_.force_loop_lag && tau > 0.0) ? 1.0 - std::exp(-period_ / tau) : 1.0;
  state_.force(0) += alpha * (commanded_ - state_.force(0));
  state_.time += period_;
  sense();
}

void ExoFingerSim::sense() noexcept {
  ExoFingerModel::JointVector q;
  const ExoFingerModel::TaskVector x = trajectory_.at(state_.time);
  model_.inverse(x, q);
  model_.forward(q, data_);
  state_.q = q;
  if (!data_.in_range) state_.fault = Fault::kOutOfRange;
  // Virtual work: tau_finger . dx = F dl_x with dq = J^-1 dx  =>  tau_finger = J^-T S^T F.
  const ExoFingerModel::JointVector joint_force = model_.selection().transpose() * state_.force;
  state_.finger_torque = regularizedSolve(data_.J.transpose().eval(), joint_force);
}

bool ExoFingerSim::finished() const noexcept {
  return state_.time >= trajectory_.startTime() + trajectory_.duration() - 0.5 * period_;
}

}  // namespace uhaptics
