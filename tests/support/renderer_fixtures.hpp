#pragma once
// Renderer set-ups that several suites test against: the TAU's LQR wall designed at home, the finger
// exoskeleton's underactuated-renderer gains.
#include "device_models.hpp"
#include "uhaptics/renderers/tau_wall_design.hpp"
#include "uhaptics/renderers/underactuated_renderers.hpp"

namespace uhaptics::test {

/// The LQR wall designed at the TAU's home pose with the default weights, once per test program.
inline const LqrWallDesign& tauHomeDesign() {
  static const LqrWallDesign d = designLqrWall(tauModel(), tauModel().homePose());
  return d;
}
inline const LqrWallGains& tauHomeGains() { return tauHomeDesign().gains; }

/// Z_x = zx I, Z_q = zq and the model's force limit, for the exoskeleton's renderers.
inline UnderactuatedGains<ExoFingerModel> exoGains(double zx, double zq) {
  UnderactuatedGains<ExoFingerModel> g;
  g.Zx = zx * Mat2::Identity();
  g.Zq(0, 0) = zq;
  g.force_limit = exoModel().effortLimits();
  return g;
}

}  // namespace uhaptics::test
