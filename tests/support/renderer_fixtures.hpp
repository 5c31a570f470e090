#pragma once
// Renderer set-ups that several suites test against: the TAU's LQR wall designed at home, the finger
// exoskeleton's underactuated-renderer gains.
#include "device_models.hpp"
#include "uhaptics/renderers/tau_wall.hpp"
#include "uhaptics/renderers/underactuated_renderers.hpp"

namespace uhaptics::test {

/// The LQR wall designed at the TAU's home pose with the default weights, once per test program.
inline const LqrWallGains& tauHomeGains() {
  static const LqrWallGains g = designLqrWall(tauModel(), tauModel().homePose());
  return g;
}

/// Z_x = zx I, Z_q = zq and the model's force limit, for the exoskeleton's renderers.
inline UnderactuatedGains<ExoFingerModel> exoGains(double zx, double zq) {
  UnderactuatedGains<ExoFingerModel> g;
  g.Zx = zx * Mat2::Identity();
  g.Zq(0, 0) = zq;
  g.force_limit = exoModel().forceLimit();
  return g;
}

}  // namespace uhaptics::test
