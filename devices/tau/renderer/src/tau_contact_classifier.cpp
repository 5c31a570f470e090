#include "uhaptics/renderers/tau_contact_classifier.hpp"

#include <algorithm>
#include <Eigen/Cholesky>
#include <cmath>
#include <limits>

#include "uhaptics/core/decompositions.hpp"
#include "uhaptics/core/fault.hpp"

namespace uhaptics {

namespace {

// Depth the tool must travel into a contact before its stiffness is estimated: four encoder counts
// at the tool (about 0.05 mm each), so quantization does not fake a stiff surface.
constexpr double kProbeDepth = 2e-4;  // m
// New forces the probe's fit needs at least: one encoder step moves the tool up to 0.25 mm, the
// whole probe depth, and a fit through two or three points reads anything.
constexpr int kProbeSamples = 8;
// Added to the probe's position covariance [m^2]: a direction the tool moved less than 5 um in
// says nothing of the surface's stiffness there.
constexpr double kProbeRegularization = 2.5e-11;
// Below this force the application's force says nothing about its surface: the session
// statistics' contact threshold, 8 um of depth at 6000 N/m.
constexpr double kTrackForce = 0.05;  // N
// The application force the wall keeps: its plane lies kHoldForce / k under the proxy, so a held
// tool stays inside the application's surface and its force keeps saying where that surface is
// (held on the proxy's own surface, the LQR's integral action would bring that force to zero, and
// the plane could no longer follow). 0.1 mm at 4800 N/m, a tenth of the paper's 1 mm bound; above
// contact_force, so the application's own contact does not flicker; and above the jitter of CHAI3D's
// proxy (its epsilon, 1e-4 world units: 0.6 N at 6000 N/m in a world in device units).
constexpr double kHoldForce = 0.5;  // N
// The normal turns toward the application's force (friction removed) with these gains per new
// force. Along the proxy's path (a surface curving under a sliding proxy): kPathGain, 20 ms, which
// lags a tool sliding at 15 mm/s over a 15 mm radius by 1 deg. Across the path: kSlowGain, 200 ms,
// so the proxy's jitter averages out. A proxy with no path (stuck, or in a concave edge, whose
// faces' forces across the wall's normal the spring renders) does not turn it at all. While
// probing, before the wall holds anything: kProbeGain, 10 ms.
constexpr double kPathGain = 0.05;
constexpr double kSlowGain = 0.005;
constexpr double kProbeGain = 0.1;
// The proxy's path: the chord over this length of it (long against the proxy's jitter, short
// against curvature: the chord of a 15 mm radius is 1 deg off its tangent).
constexpr double kChord = 5e-4;  // m
// The steepest rise off the wall's plane one step of the proxy's path may make, against its run
// along the plane (30 deg: the normal follows a steeper surface by its force and by the steps that
// do fit, and a hop of CHAI3D's proxy is 0.1 mm against a slow slip's micrometres).
constexpr double kMaxSlope = 0.577;
// The plane's offset along its normal follows the proxy with this gain per new force (5 ms), and
// at most 50 mm/s (twice a brisk hand): a proxy jumping across a mesh's thin feature gives the LQR a
// ramp, not a step.
constexpr double kOffsetGain = 0.2;
constexpr double kPlaneStep = 5e-5;  // m per tick
// While the wall holds the tool and the application feels no contact, the plane sinks this fast
// until it does (past a convex crest the real surface falls away below the plane).
constexpr double kCreepSpeed = 0.01;  // m/s
// The wall's command saturated this long without a break: the device cannot hold the contact
// there; the spring (scaled into the torque limits) takes the contact over.
constexpr int kOverloadTicks = 20;

}  // namespace

TauContactClassifier::TauContactClassifier(const Options& options) : options_(options) {
  const auto positive = [](double v) { return v > 0.0 && std::isfinite(v); };
  if (!positive(options.stiff_threshold)) throw Error("TauContactClassifier: stiff_threshold must be finite and > 0");
  if (!positive(options.contact_force)) throw Error("TauContactClassifier: contact_force must be finite and > 0");
  if (options.release_ticks < 1) throw Error("TauContactClassifier: release_ticks must be >= 1");
  if (!positive(options.nominal_stiffness))
    throw Error("TauContactClassifier: nominal_stiffness must be finite and > 0");
  if (!positive(options.servo_period)) throw Error("TauContactClassifier: servo_period must be finite and > 0");
  reset();
}

void TauContactClassifier::reset() noexcept {
  events_ = Events{};
  state_ = State::kFree;
  held_ = false;
  entry_depth_ = 0.0;
  quiet_ticks_ = 0;
  last_force_.setZero();
  last_position_.setZero();
  frames_ticks_ = 0;
  overload_ticks_ = 0;
  probe_ = ProbeFit{};
  stiffness_ = 0.0;
  normal_ = Vec3::UnitZ();
  proxy_.setZero();
  has_proxy_ = false;
  trail_head_ = 0;
  trail_count_ = 0;
  surface_ = SurfaceContact{};
}

void TauContactClassifier::setSpringLimit(double limit) noexcept {
  options_.spring_limit = limit > 0.0 ? limit : std::numeric_limits<double>::infinity();
}

void TauContactClassifier::release() noexcept {
  if (state_ == State::kLqr) events_.released = true;
  state_ = State::kFree;
  surface_.active = false;
}

bool TauContactClassifier::endContact() noexcept {
  const bool released = state_ == State::kLqr;
  state_ = State::kFree;
  held_ = false;
  surface_.active = false;
  return released;
}

double TauContactClassifier::perTick(double gain) const noexcept {
  // The filters' gains are per servo tick; an application slower than the servo sends a new force
  // every few ticks, and each then counts for all of them (time constants in time, not in frames).
  return frames_ticks_ <= 1 ? gain : 1.0 - std::pow(1.0 - gain, std::min(frames_ticks_, 50));
}

void TauContactClassifier::trackSurface(const Vec3& force, const Vec3& position, double stiffness,
                                        double turn_gain) noexcept {
  // A force below kTrackForce, or one pointing into the surface (proxy jitter), is no evidence.
  const double magnitude = force.norm();
  if (!(magnitude >= kTrackForce) || !(force.dot(normal_) > 0.0)) {
    has_proxy_ = false;
    return;
  }
  // The application's proxy: its force is F = k (proxy - tool).
  const Vec3 proxy = position + force / stiffness;
  // The trail records the proxy's path with each step's rise off the surface limited to kMaxSlope
  // of its run along it. CHAI3D's finger proxy hops off a face by up to its epsilon in a single
  // step; over a slow slip's few micrometres of run that hop is no slope of the surface, and in a
  // kChord chord it would read as one (0.1 mm in 0.5 mm: 11 deg). A surface that really curves
  // rises by run^2 / 2R in a step, far inside the limit.
  Vec3 point = proxy;
  if (trail_count_ > 0) {
    const Vec3 step = proxy - proxy_;
    const double rise = step.dot(normal_);
    const double run = (step - rise * normal_).norm();
    const double limit = kMaxSlope * run;
    point = trail_[trail_head_] + step - (rise - std::clamp(rise, -limit, limit)) * normal_;
  }
  proxy_ = proxy;
  has_proxy_ = true;
  trail_head_ = (trail_head_ + 1) % kTrailLength;
  trail_[trail_head_] = point;
  trail_count_ = std::min(trail_count_ + 1, kTrailLength);
  // The proxy's path: the chord back to where it was kChord ago, if that is in the trail (a proxy
  // that moved less is stuck by static friction, or stopped in a concave edge).
  Vec3 path = Vec3::Zero();
  for (int i = 1; i < trail_count_; ++i) {
    const Vec3 travel = point - trail_[(trail_head_ + kTrailLength - i) % kTrailLength];
    const double length = travel.norm();
    if (length >= kChord) {
      path = travel / length;
      break;
    }
  }
  // Friction: CHAI3D's finger proxy, slipping, sits on its friction cone's rim on the way to the
  // tool, so its tangential force points against its own motion, which lies in the surface (normal
  // to it). F's component along the path is that friction and is removed; what is left is normal to
  // the path, as the surface normal is.
  // A proxy that has not moved kChord while the wall owns the contact is stuck (static friction,
  // or a concave edge): the surface under it is not changing, and its force's direction is its pull
  // on the tool (up to the friction cone's rim, or toward the other face), so the normal stays.
  if (state_ == State::kLqr && path.isZero()) return;
  const Vec3 normal_force = force - force.dot(path) * path;
  const double length = normal_force.norm();
  if (!(length > 0.0)) return;
  const Vec3 turn = normal_force / length - normal_;
  const Vec3 along_path = turn.dot(path) * path;  // = -(n . path) path: geometry, not F
  const double weight = std::min(1.0, length / kHoldForce);  // a small force counts in proportion
  const Vec3 normal = normal_ + perTick(kPathGain) * along_path + weight * perTick(turn_gain) * (turn - along_path);
  const double norm = normal.norm();
  if (norm > 1e-9 && std::isfinite(norm)) normal_ = normal / norm;
}

void TauContactClassifier::startContact(const Vec3& force, WallMode mode) noexcept {
  state_ = mode == WallMode::kSpring ? State::kSpring : State::kProbing;
  normal_ = force.normalized();
  has_proxy_ = false;
  trail_count_ = 0;
  quiet_ticks_ = 0;
}

void TauContactClassifier::ProbeFit::start(const Vec3& position, const Vec3& normal) noexcept {
  *this = ProbeFit{};
  origin = position;
  onset_normal = normal;
}

void TauContactClassifier::ProbeFit::add(const Vec3& position, const Vec3& force) noexcept {
  const Vec3 x = position - origin;
  ++count;
  sum_x += x;
  sum_f += force;
  sum_xx.noalias() += x * x.transpose();
  sum_xf.noalias() += x * force.transpose();
  deepest = std::max(deepest, -onset_normal.dot(x));
}

double TauContactClassifier::ProbeFit::stiffness() const noexcept {
  if (count < 2) return 0.0;
  // F = F0 - K x by least squares over the samples: K^T = -Cxx^-1 Cxf, with Cxx regularized for
  // directions the tool did not move in (they contribute no stiffness).
  const double inv = 1.0 / count;
  const Vec3 mean_x = inv * sum_x, mean_f = inv * sum_f;
  const Mat3 cxx = inv * sum_xx - mean_x * mean_x.transpose() + kProbeRegularization * Mat3::Identity();
  const Mat3 cxf = inv * sum_xf - mean_x * mean_f.transpose();
  const Mat3 k_t = -cxx.ldlt().solve(cxf);
  // A surface pushes back along its normal at k; a proxy held by static friction pulls the tool
  // back sideways at the same k, a slipping one at less: the stiffest direction is the surface's.
  // This reads k when the tool moved along the normal and across it (a quantized pose jumping
  // sideways), but only k (n.u)(1 + n.u) / 2 when it moved along one line u.
  const Mat3 k_sym = 0.5 * (k_t + k_t.transpose());
  Vec3 k_eigen;  // ascending
  const double k_matrix = symmetricEigen(k_sym, k_eigen) ? k_eigen(2) : std::numeric_limits<double>::quiet_NaN();
  // Along the mean force's direction (the surface's normal, friction averaged): the slope of n.F
  // against n.x. This reads k for motion along one line, and less when the tool also jumps
  // sideways (the jumps load the fit's depth but, friction aside, not its force).
  double k_normal = 0.0;
  const double length = sum_f.norm();
  if (length > 0.0) {
    const Vec3 n = sum_f / length;
    const double var = n.dot(cxx * n);
    if (var > 0.0) k_normal = -n.dot(cxf * n) / var;
  }
  // Each reads low in the other's case: the larger is the better evidence.
  const double k = std::max(k_matrix, k_normal);
  return std::isfinite(k) ? k : 0.0;
}

void TauContactClassifier::update(const Vec3& force_in, const Vec3& position_in, WallMode mode) noexcept {
  events_ = Events{};
  const bool finite = force_in.allFinite() && position_in.allFinite();
  const Vec3 force = finite ? force_in : Vec3::Zero();
  const Vec3 position = finite ? position_in : last_position_;
  const double magnitude = force.norm();
  // A force the application has not sent before was computed from the position it read last; a
  // repeated one is older and says nothing new.
  const bool fresh = (force.array() != last_force_.array()).any();
  // Servo ticks since the last new force, this one included, counted while that force was a
  // contact (a force that stayed zero held no information to wait for).
  frames_ticks_ = last_force_.norm() >= kTrackForce ? frames_ticks_ + 1 : 1;

  if (state_ == State::kFree) {
    if (magnitude > options_.contact_force && std::isfinite(magnitude)) {
      startContact(force, mode);
      probe_.start(position, normal_);
      probe_.add(position, force);
    }
  } else {
    if (mode == WallMode::kSpring && state_ != State::kSpring) {
      release();  // switched to the spring mid-contact
      state_ = State::kSpring;
    }
    // Out of contact: the wall does not hold the tool and the application feels (almost) nothing;
    // or the wall holds it where the application feels nothing at all (a plane above its surface).
    const bool out = held_ ? magnitude < kTrackForce : magnitude < 0.5 * options_.contact_force;
    quiet_ticks_ = out ? quiet_ticks_ + 1 : 0;
    if (quiet_ticks_ >= options_.release_ticks) {
      release();
    } else if (state_ == State::kLqr && overload_ticks_ >= kOverloadTicks && stiffness_ <= options_.spring_limit) {
      release();
      state_ = State::kSpring;
      events_.overload = true;
    } else if (state_ == State::kProbing && fresh) {
      // Stiffness: a least-squares fit of the new forces against the positions they were computed
      // at (ProbeFit::stiffness), over every sample since the onset, not a secant between two of
      // them: the encoders' pose moves in steps of 0.05-0.25 mm, sideways too, and CHAI3D's proxy
      // answers each sideways step with a friction force of either sign. The proxy is placed with
      // the nominal stiffness until the probe has measured the scene's.
      //
      // The probe measures one surface pushing the tool out while the tool goes in: a force against
      // the normal (the contact began on an effect pulling the tool in, such as a magnet outside its
      // object, whose force turns round at the surface) restarts it along the new force.
      if (!(normal_.dot(force) > 0.0)) {
        const bool restart = magnitude > options_.contact_force;
        if (restart) startContact(force, mode);
        probe_.start(position, normal_);
        if (restart) probe_.add(position, force);
      } else {
        trackSurface(force, position, options_.nominal_stiffness, kProbeGain);
        probe_.add(position, force);
      }
      if (probe_.deepest >= kProbeDepth && probe_.count >= kProbeSamples) {
        const double k = probe_.stiffness();
        stiffness_ = std::isfinite(k) ? std::max(0.0, k) : 0.0;
        if (stiffness_ > 0.0 && (stiffness_ >= options_.stiff_threshold || mode == WallMode::kLqr)) {
          state_ = State::kLqr;
          overload_ticks_ = 0;
          // The plane's first normal: the probe's mean force, in which the friction of a pose
          // jumping sideways averages out, rather than the tracked normal of its last forces.
          const double mean = probe_.sum_f.norm();
          if (mean > 0.0 && std::isfinite(mean)) normal_ = probe_.sum_f / mean;
          surface_.active = true;
          surface_.normal = normal_;
          surface_.point = position + (force - kHoldForce * normal_) / stiffness_;
          events_.engaged = true;
        } else {
          state_ = State::kSpring;  // a soft surface: the spring renders the whole contact
          events_.soft_contact = true;
          events_.soft_stiffness = stiffness_;
        }
      }
    } else if (state_ == State::kLqr) {
      // The plane: kHoldForce / k under the proxy, normal to the tracked normal; held without any
      // force from the application, it sinks.
      Vec3 step = Vec3::Zero();
      double gain = 1.0;
      if (fresh) trackSurface(force, position, stiffness_, kSlowGain);
      if (fresh && has_proxy_) {
        step = proxy_ - (kHoldForce / stiffness_) * normal_ - surface_.point;
        gain = perTick(kOffsetGain);
      } else if (held_ && magnitude < kTrackForce) {
        step = -kCreepSpeed * options_.servo_period * normal_;
      }
      const double along = normal_.dot(step);
      const double most = kPlaneStep * std::max(1, std::min(frames_ticks_, 50));  // 50 mm/s
      step += (std::min(most, std::max(-most, gain * along)) - along) * normal_;
      surface_.point += step;
      surface_.normal = normal_;
    }
  }
  if (fresh) {
    last_force_ = force;
    last_position_ = position;
    frames_ticks_ = 0;
  }
  if (state_ != State::kLqr) surface_.active = false;
}

void TauContactClassifier::follow(const SurfaceContact& surface) noexcept {
  events_ = Events{};
  const bool was = state_ == State::kLqr;
  surface_ = surface;
  state_ = surface_.active ? State::kLqr : State::kFree;
  events_.engaged = surface_.active && !was;
  events_.released = !surface_.active && was;
}

void TauContactClassifier::wallTicked(const WallCommand& wall) noexcept {
  const bool was_held = held_;
  held_ = state_ == State::kLqr && wall.in_contact;
  overload_ticks_ = held_ && wall.saturated ? overload_ticks_ + 1 : 0;
  events_.held = held_;
  events_.hold_started = false;
  events_.saturated = false;
  events_.penetration = 0.0;
  if (!held_) return;
  if (!was_held) {
    entry_depth_ = wall.penetration;
    events_.hold_started = true;
    events_.entry_depth = wall.penetration;
  }
  if (wall.penetration <= kSettledDepth) entry_depth_ = 0.0;
  events_.penetration = std::max(0.0, wall.penetration - entry_depth_);
  events_.saturated = wall.saturated;
}

void TauContactClassifier::holdLost() noexcept { held_ = false; }

}  // namespace uhaptics
