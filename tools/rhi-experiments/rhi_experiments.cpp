#include "rhi_experiments.hpp"

#include <Eigen/Cholesky>
#include <cmath>
#include <limits>

#include "uhaptics/core/self_motion.hpp"
#include "uhaptics/tools/parallel.hpp"

namespace uhaptics::rhi {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

Rhi4Controller::Options paperOptions(FmeEllipsoidMode mode, const Vec2& u) {
  Rhi4Controller::Options o;  // mu = 5, beta = 20, K_d = 0.1, eps1 = 0.7, eps2 = 0.95, rho = 0.003
  o.mode = mode;
  o.motion_direction = u;
  return o;
}
}  // namespace

Rhi4Model loadRhi4(const std::string& params_dir) { return Rhi4Model::fromFile(params_dir + "/rhi4.json", "rhi4"); }
Planar3Model loadPlanar3(const std::string& params_dir) {
  return Planar3Model::fromFile(params_dir + "/planar3.json", "planar3");
}

template <int N>
Vec<N> inverseKinematics(const PlanarLinkageModel<N>& model, const Vec<N>& q_start, const Vec2& x) {
  Vec<N> q = q_start;
  const double err = fme::projectOnto(model, q, x);
  if (!(err < 1e-9)) throw Error("inverse kinematics: point not reached (error " + std::to_string(err) + " m)");
  return q;
}
template Vec<3> inverseKinematics<3>(const PlanarLinkageModel<3>&, const Vec<3>&, const Vec2&);
template Vec<4> inverseKinematics<4>(const PlanarLinkageModel<4>&, const Vec<4>&, const Vec2&);

// ---- 3-DoF example ---------------------------------------------------------------------------
ExampleResult runExample3(const Planar3Model& model, double duration, double dt) {
  ExampleResult r;
  const Vec3 limits = model.torqueLimits();
  const Vec3 w2 = fme::inverseSquaredLimits(limits);
  const Vec3 q0 = model.home();
  model.forward(q0, r.x_end);
  Mat<2, 3> J;
  model.jacobian(q0, J);
  Mat2 fme0;
  if (!fme::weightedFme(J, w2, fme0)) throw Error("3-DoF example: singular initial configuration");
  const auto scales = fme::ellipsoidScales(fme0, 5.0);
  r.K = scales.major;
  r.zeta = scales.minor;
  const Vec2 force_dir(1.0, 0.0);  // F_e acts along x: the motion/contact axis
  fme::axisAlignedEllipsoid(force_dir, r.zeta, r.K, r.free_fme);
  fme::axisAlignedEllipsoid(force_dir, r.K, r.zeta, r.stiff_fme);

  const char* names[3] = {"initial", "free", "stiff"};
  for (int c = 0; c < 3; ++c) {
    ExampleConfiguration& cfg = r.configs[static_cast<std::size_t>(c)];
    cfg.name = names[c];
    cfg.q = q0;
    const Mat2& target = c == 2 ? r.stiff_fme : r.free_fme;
    if (c > 0) {
      const auto opt = fme::optimizeSelfMotion(model, cfg.q, r.x_end, w2, target);
      if (!opt.valid) throw Error(std::string("3-DoF example: optimization failed for ") + names[c]);
    }
    model.jacobian(cfg.q, J);
    fme::weightedFme(J, w2, cfg.fme);
    fme::logDetDivergence(cfg.fme, target, cfg.nu);
  }
  const long steps = std::lround(duration / dt);
  r.samples.reserve(static_cast<std::size_t>(steps + 1));
  for (long k = 0; k <= steps; ++k) {
    ExampleSample s;
    s.t = static_cast<double>(k) * dt;
    const Vec2 F(3.5 * std::sin(M_PI * s.t / 2.0), 0.0);
    s.demanded_x = F(0);
    for (std::size_t c = 0; c < 3; ++c) {
      model.jacobian(r.configs[c].q, J);
      Vec3 tau = J.transpose() * F;
      const double alpha = scaleIntoBox(tau, limits);
      s.tau[c] = tau;
      s.force_x[c] = alpha * F(0);
      r.configs[c].peak_force = std::max(r.configs[c].peak_force, std::abs(s.force_x[c]));
      r.configs[c].min_alpha = std::min(r.configs[c].min_alpha, alpha);
    }
    r.samples.push_back(s);
  }
  return r;
}

// ---- closed loop -------------------------------------------------------------------------------
ClosedLoop::ClosedLoop(const Rhi4Model& model, const Rhi4Controller::Options& options, const PalpationSetup& setup)
    : setup_(setup), sim_(model, setup.substep), ctrl_(model, model.torqueLimits(), model.home(), options) {}

EndEffectorLoad ClosedLoop::handAt(const Vec2& anchor) const {
  EndEffectorLoad load;
  load.anchor = anchor;
  load.stiffness = setup_.hand_stiffness * Mat2::Identity();
  load.damping = setup_.hand_damping * Mat2::Identity();
  return load;
}

void ClosedLoop::tick(const Vec2& anchor, bool wall_on) { tick(handAt(anchor), wall_on); }

void ClosedLoop::tick(const EndEffectorLoad& load, bool wall_on) {
  const Vec4 q = sim_.position(), qd = sim_.velocity();
  const Vec2 x = sim_.endEffectorPosition();
  const double penetration = (x - setup_.x0).dot(setup_.u);
  force_ = wall_on && penetration > 0.0 ? Vec2(-setup_.wall_stiffness * penetration * setup_.u) : Vec2::Zero();
  ctrl_.tick(t_, q, qd, force_, tau_);
  sim_.setLoad(load);
  sim_.step(tau_, setup_.servo_dt);
  t_ += setup_.servo_dt;
}

LoopSample ClosedLoop::sample() const {
  const auto& st = ctrl_.status();
  return {t_, sim_.endEffectorPosition(), st.force, force_.norm(), tau_, st.tau_null, st.tau_null_command,
          st.observer, st.omega, st.cost, st.alpha};
}

namespace {
ClosedLoop settledLoop(const Rhi4Model& model, const Rhi4Controller::Options& options, const PalpationSetup& setup,
                       const Vec4& q_guess, const Vec2& x_start, double settle_time) {
  ClosedLoop loop(model, options, setup);
  loop.device().reset(inverseKinematics(model, q_guess, x_start));
  const long n = std::lround(settle_time / setup.servo_dt);
  for (long k = 0; k < n; ++k) loop.tick(x_start, false);
  return loop;
}
}  // namespace

PalpationCase runPalpation(const Rhi4Model& model, FmeEllipsoidMode mode, const PalpationSetup& setup, int trials) {
  PalpationCase pc;
  pc.name = mode == FmeEllipsoidMode::kStiff ? "stiff" : "free";
  const auto options = paperOptions(mode, setup.u);
  const Vec4 limits = model.torqueLimits();

  // 1. Reconfigure at x0, then push into the wall with the hand: anchor ramps 3 cm along u.
  ClosedLoop loop = settledLoop(model, options, setup, model.home(), setup.x0, setup.settle_time);
  pc.q_settled = loop.device().position();
  Mat<2, 4> J;
  model.jacobian(pc.q_settled, J);
  pc.capability = fme::maxForceAlong(J, limits, setup.u);
  const double t_start = loop.time();
  while (loop.time() < t_start + 2.7) {
    const double s = std::clamp((loop.time() - t_start - 0.2) / 2.0, 0.0, 1.0);
    loop.tick(setup.x0 + 0.03 * s * setup.u, true);
    const LoopSample smp = loop.sample();
    pc.peak_force = std::max(pc.peak_force, std::abs(smp.force.dot(setup.u)));
    pc.push.push_back(smp);
  }

  // 2. Identification (paper Sec. IV): start 5 cm before x0, push with a constant force of 0.5-1.5 N
  // along u on a guide (stiff across u), regress F = M_x a + Phi v on the samples near x0.
  const Vec2 start = setup.x0 - 0.05 * setup.u;
  const Mat2 across = Mat2::Identity() - setup.u * setup.u.transpose();
  // Regressors [a, v, 1]: the paper fits M_x and a viscous Phi; joint Coulomb friction reflects as
  // a constant force during a push in one direction, fitted here as a third term so it does not
  // bias the other two.
  Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  double inertia_sum = 0.0, friction_sum = 0.0;
  int inertia_count = 0;
  for (int i = 0; i < trials; ++i) {
    IdentificationTrial trial;
    trial.push_force = trials > 1 ? 0.5 + static_cast<double>(i) / (trials - 1) : 1.0;
    ClosedLoop id = settledLoop(model, options, setup, pc.q_settled, start, 1.5);
    EndEffectorLoad guide;
    guide.bias = trial.push_force * setup.u;
    guide.anchor = start;
    guide.stiffness = 5000.0 * across;
    guide.damping = 50.0 * across;
    bool crossed = false;
    const double t0 = id.time();
    while (id.time() < t0 + 3.0) {
      id.tick(guide, false);
      const auto& dev = id.device();
      const double xu = (dev.endEffectorPosition() - setup.x0).dot(setup.u);
      if (std::abs(xu) <= 0.02) {
        trial.samples.push_back({xu, dev.endEffectorVelocity().dot(setup.u),
                                 dev.endEffectorAcceleration().dot(setup.u), trial.push_force});
      }
      if (!crossed && xu >= 0.0) {
        crossed = true;
        Mat<4, 4> Mq;
        Mat<2, 4> Jx;
        model.massMatrix(dev.position(), Mq);
        model.jacobian(dev.position(), Jx);
        const Mat<4, 2> MinvJt = Mq.llt().solve(Jx.transpose());
        const Mat2 lambda = (Jx * MinvJt).inverse();
        const Mat<4, 2> Jsharp = MinvJt * lambda;
        inertia_sum += setup.u.dot(lambda * setup.u);
        friction_sum += setup.u.dot(Jsharp.transpose() * model.parameters().viscous_friction.asDiagonal() * Jsharp *
                                    setup.u);
        ++inertia_count;
      }
      if (xu > 0.025) break;
    }
    for (const auto& s : trial.samples) {
      const Eigen::Vector3d row(s[2], s[1], 1.0);
      normal += row * row.transpose();
      rhs += row * s[3];
    }
    pc.trials.push_back(std::move(trial));
  }
  pc.inertia_model = inertia_count ? inertia_sum / inertia_count : kNaN;
  pc.friction_model = inertia_count ? friction_sum / inertia_count : kNaN;
  const Eigen::Vector3d theta = normal.ldlt().solve(rhs);
  pc.inertia_identified = theta(0);
  pc.friction_identified = theta(1);
  pc.coulomb_identified = theta(2);
  double sq = 0.0;
  std::size_t n = 0;
  for (const auto& trial : pc.trials)
    for (const auto& s : trial.samples) {
      const double e = s[3] - theta(0) * s[2] - theta(1) * s[1] - theta(2);
      sq += e * e;
      ++n;
    }
  pc.fit_rms = n ? std::sqrt(sq / static_cast<double>(n)) : kNaN;
  return pc;
}

// ---- workspace map ----------------------------------------------------------------------------
std::vector<WorkspacePoint> workspaceRatioMap(const Rhi4Model& model, double step, double max_radius, const Vec2& u,
                                              unsigned threads) {
  std::vector<WorkspacePoint> points;
  const Vec2 base = model.parameters().base;
  const int n = static_cast<int>(std::floor(max_radius / step));
  for (int i = -n; i <= n; ++i)
    for (int j = -n; j <= n; ++j) {
      const Vec2 d(i * step, j * step);
      if (d.norm() <= max_radius) points.push_back({base + d, kNaN, kNaN, kNaN});
    }
  const Vec4 limits = model.torqueLimits();
  const Vec4 w2 = fme::inverseSquaredLimits(limits);
  Mat<2, 4> J;
  model.jacobian(model.home(), J);
  Mat2 fme0;
  fme::weightedFme(J, w2, fme0);
  const auto scales = fme::ellipsoidScales(fme0, 5.0);
  Mat2 free_fme, stiff_fme;
  fme::axisAlignedEllipsoid(u, scales.minor, scales.major, free_fme);
  fme::axisAlignedEllipsoid(u, scales.major, scales.minor, stiff_fme);
  fme::SelfMotionOptions opt;
  opt.max_iterations = 1500;
  tools::parallelFor(points.size(), threads, [&](std::size_t k) {
    WorkspacePoint& p = points[k];
    Vec4 q0 = model.home();
    if (fme::projectOnto(model, q0, p.x) > 1e-9) return;
    Mat<2, 4> Jp;
    Vec4 q = q0;
    if (!fme::optimizeSelfMotion(model, q, p.x, w2, free_fme, opt).valid) return;
    model.jacobian(q, Jp);
    p.free_force = fme::maxForceAlong(Jp, limits, u);
    q = q0;
    if (!fme::optimizeSelfMotion(model, q, p.x, w2, stiff_fme, opt).valid) return;
    model.jacobian(q, Jp);
    p.stiff_force = fme::maxForceAlong(Jp, limits, u);
    p.ratio = p.stiff_force / p.free_force;
  });
  return points;
}

// ---- transition -------------------------------------------------------------------------------
TransitionRun runTransition(const Rhi4Model& model, bool smooth, const PalpationSetup& setup) {
  TransitionRun run;
  run.smooth = smooth;
  auto options = paperOptions(FmeEllipsoidMode::kAuto, setup.u);
  options.transition.smooth = smooth;
  ClosedLoop loop = settledLoop(model, options, setup, model.home(), setup.x0, setup.settle_time);
  run.transition_duration =
      options.transition.rho * (loop.controller().freeEllipsoid() - loop.controller().stiffEllipsoid()).norm();
  // Hold, press 3 cm into the wall (the demand exceeds the free configuration's capability), hold,
  // withdraw out of contact, hold.
  const double t0 = loop.time();
  Vec4 previous = Vec4::Zero(), previous_applied = Vec4::Zero();
  bool first = true;
  while (loop.time() < t0 + 7.5) {
    const double t = loop.time() - t0;
    double depth = 0.0;
    if (t < 0.5) depth = 0.0;
    else if (t < 2.0) depth = 0.03 * (t - 0.5) / 1.5;
    else if (t < 4.0) depth = 0.03;
    else if (t < 5.5) depth = 0.03 - 0.035 * (t - 4.0) / 1.5;
    else depth = -0.005;
    loop.tick(setup.x0 + depth * setup.u, true);
    LoopSample s = loop.sample();
    s.t = t;
    if (!first) {
      const double jump = (s.tau_null_command - previous).cwiseAbs().maxCoeff();
      if (jump > run.max_null_torque_jump) {
        run.max_null_torque_jump = jump;
        run.jump_time = t;
      }
      run.max_applied_null_jump =
          std::max(run.max_applied_null_jump, (s.tau_null - previous_applied).cwiseAbs().maxCoeff());
    }
    first = false;
    previous = s.tau_null_command;
    previous_applied = s.tau_null;
    run.samples.push_back(s);
  }
  return run;
}

}  // namespace uhaptics::rhi
