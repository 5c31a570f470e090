// Stress suite, TAU: the LQR wall and the spring wall under random, out-of-range, non-finite and
// singular joint readings, random surfaces and weights and stiffnesses spanning 1e0..1e9.
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>

#include "stress_support.hpp"
#include "uhaptics/renderers/tau_wall.hpp"

using namespace uhaptics;

namespace {
const TauModel& model() {
  static const TauModel m = TauModel::load(std::string(UHAPTICS_PARAMS_DIR) + "/tau.json");
  return m;
}

Vec3 randomUnit(stress::AdversarialSource& src) {
  Vec3 v(src.uniform(-1, 1), src.uniform(-1, 1), src.uniform(-1, 1));
  return v.norm() > 1e-3 ? Vec3(v.normalized()) : Vec3(Vec3::UnitZ());
}

// A pose drawn from the workspace widened to three times its size, with special values (NaN, Inf,
// 1e300, ...) 10 % of the time per coordinate.
Vec6 adversarialPose(stress::AdversarialSource& src) {
  const double h = model().workspaceHalfSide(), a = model().workspaceHalfAngle();
  Vec6 p = model().homePose();
  for (int i = 0; i < 3; ++i) p(i) += src.around(-h, h);
  for (int i = 3; i < 6; ++i) p(i) += src.around(-a, a);
  return p;
}

// Joint readings: IK of an adversarial pose when it exists, else an adversarial joint vector
// (mostly without any assembly: the forward kinematics must refuse it).
Vec6 adversarialJoints(stress::AdversarialSource& src) {
  Vec6 q;
  if (model().inverse(adversarialPose(src), q) == Fault::kNone) return q;
  for (int i = 0; i < 6; ++i) q(i) = model().homeJoints()(i) + src.around(-0.5, 0.5);
  return q;
}

struct Episode {
  Vec6 q;
  SurfaceContact contact;
};

// Checks one command against the contract: a fault with an exactly-zero command, or a finite
// command within the joint torque limits.
void judge(const WallCommand& cmd, stress::Tally& t) {
  ++t.cases;
  if (cmd.fault != Fault::kNone) {
    ++t.faults;
    if (!cmd.torque.isZero(0.0)) ++t.violations;
    return;
  }
  if (cmd.saturated) ++t.clamped;
  const bool within = cmd.torque.allFinite() &&
                      (cmd.torque.cwiseAbs().array() <= model().torqueLimit().array()).all();
  if (!within) ++t.violations;
}

// Sequences of ticks (the renderers are stateful: observer, contact entry, integrator): a smooth
// random motion near a random surface, glitched by adversarial readings, contacts and poses.
template <class Renderer>
void hammer(Renderer& r, stress::AdversarialSource& src, int episodes, int ticks, stress::Tally& t) {
  TauData device(model());
  for (int e = 0; e < episodes; ++e) {
    r.reset();
    Vec6 q = adversarialJoints(src);
    SurfaceContact c;
    c.active = src.uniform(0, 1) < 0.8;
    c.normal = randomUnit(src);
    c.point = model().homePose().head<3>() + Vec3(src.uniform(-0.03, 0.03), src.uniform(-0.03, 0.03),
                                                  src.uniform(-0.03, 0.03));
    Vec6 velocity;
    for (int i = 0; i < 6; ++i) velocity(i) = src.uniform(-1.0, 1.0) * model().servoPeriod();  // up to 1 rad/s
    for (int k = 0; k < ticks; ++k) {
      Vec6 reading = q;
      SurfaceContact ck = c;
      const double u = src.uniform(0, 1);
      if (u < 0.05) reading(static_cast<int>(src.uniform(0, 5.999))) = src.around(-3.0, 3.0);
      else if (u < 0.08) ck.normal *= src.around(0.5, 1.5);  // non-unit or non-finite normal
      else if (u < 0.10) ck.point(2) = src.around(-0.1, 0.1);
      const Vec6* pose = nullptr;
      if (src.uniform(0, 1) < 0.3) {  // the caller supplies the pose: its FK, or garbage
        if (src.uniform(0, 1) < 0.8) {
          model().forward(reading, device);
        } else {
          device.pose = adversarialPose(src);
        }
        pose = &device.pose;
      }
      judge(r.tick(reading, ck, pose), t);
      q += velocity;
    }
  }
}
}  // namespace

TEST_CASE("TAU walls: random, out-of-range, non-finite and singular states, surfaces and poses; weights "
          "and stiffnesses 1e0..1e9") {
  stress::AdversarialSource src(20261123);
  const int episodes = 20 * stress::scale(), ticks = 40;
  stress::Tally lqr{"tau LQR wall"}, lqr_paper{"tau LQR wall (paper 001 hold, bilateral)"}, spring{"tau spring wall"};
  long designs = 0, refused_designs = 0;
  for (int w = 0; w < 8; ++w) {
    LqrWallWeights weights;
    weights.velocity = src.logUniform(0, 9);
    weights.position = src.logUniform(0, 9);
    weights.integral = src.logUniform(0, 9);
    weights.torque = src.logUniform(0, 9);
    // Operating point anywhere in the workspace widened by half (outside: a clear refusal).
    Vec6 op = model().homePose();
    for (int i = 0; i < 3; ++i) op(i) += src.uniform(-1.5, 1.5) * model().workspaceHalfSide();
    for (int i = 3; i < 6; ++i) op(i) += src.uniform(-1.5, 1.5) * model().workspaceHalfAngle();
    ++designs;
    LqrWallGains gains;
    try {
      gains = designLqrWall(model(), op, weights);
    } catch (const Error&) {
      ++refused_designs;  // a clear refusal at set-up is an allowed answer
      continue;
    }
    // A design that returns must be a verified one, not a silent wrong answer.
    CHECK(gains.Kc.allFinite());
    CHECK(gains.Ki.allFinite());
    CHECK(gains.dare_residual <= 1e-8);
    LqrWallRenderer a(model(), gains);
    LqrWallRenderer b(model(), gains, LqrWallRenderer::Options{2e-4, true, false, false});
    hammer(a, src, episodes, ticks, lqr);
    hammer(b, src, episodes, ticks, lqr_paper);
  }
  for (int s = 0; s < 8; ++s) {
    SpringWallRenderer::Options o;
    o.stiffness = src.logUniform(0, 9);
    o.damping = src.uniform(0, 1) < 0.5 ? 0.0 : src.logUniform(0, 9);
    SpringWallRenderer r(model(), o);
    hammer(r, src, episodes, ticks, spring);
  }
  std::cout << "stress: tau LQR designs: " << designs << " tried, " << refused_designs
            << " refused with an Error (operating point unreachable or design failed its checks)\n";
  for (const auto* t : {&lqr, &lqr_paper, &spring}) {
    t->print();
    CHECK(t->violations == 0);
    CHECK(t->cases > 0);
  }
  // The suite must exercise both answers, or it proves nothing.
  CHECK(lqr.faults > 0);
  CHECK(lqr.faults < lqr.cases);
  CHECK(spring.clamped > 0);
}

TEST_CASE("TAU walls reject invalid parameters at set-up with a clear error") {
  SpringWallRenderer::Options o;
  o.stiffness = -1.0;
  CHECK_THROWS_AS(SpringWallRenderer(model(), o), Error);
  o.stiffness = std::nan("");
  CHECK_THROWS_AS(SpringWallRenderer(model(), o), Error);
  o.stiffness = 1e3;
  o.damping = std::numeric_limits<double>::infinity();
  CHECK_THROWS_AS(SpringWallRenderer(model(), o), Error);
  LqrWallWeights w;
  w.integral = 0.0;
  CHECK_THROWS_AS(designLqrWall(model(), model().homePose(), w), Error);
  w = LqrWallWeights{};
  w.velocity = std::nan("");
  CHECK_THROWS_AS(designLqrWall(model(), model().homePose(), w), Error);
  Vec6 nan_pose = model().homePose();
  nan_pose(4) = std::nan("");
  CHECK_THROWS_AS(designLqrWall(model(), nan_pose, LqrWallWeights{}), Error);
}

TEST_CASE("TAU LQR wall recovers after adversarial readings: a glitch never leaves it faulting") {
  // A faulting tick must leave no poisoned state behind (observer estimate, integrator): once
  // the readings are sane again the wall renders.
  stress::AdversarialSource src(99);
  const LqrWallGains gains = designLqrWall(model(), model().homePose());
  LqrWallRenderer r(model(), gains);
  const Vec6 q0 = model().homeJoints();
  SurfaceContact c;
  c.active = true;
  c.point = model().homePose().head<3>() + Vec3(0, 0, 0.0005);  // tool 0.5 mm inside the wall
  const int n = 200 * stress::scale();
  int stuck = 0;
  for (int i = 0; i < n; ++i) {
    Vec6 glitch = q0;
    for (int j = 0; j < 6; ++j)
      if (src.uniform(0, 1) < 0.5) glitch(j) = src.around(-1e3, 1e3);
    r.tick(glitch, c);
    for (int k = 0; k < 50; ++k) r.tick(q0, c);  // back at rest inside the wall
    if (r.command().fault != Fault::kNone || !r.command().in_contact) ++stuck;
  }
  std::cout << "stress: tau LQR wall: " << n << " glitches, " << stuck << " left it faulting or out of contact\n";
  CHECK(stuck == 0);
}
