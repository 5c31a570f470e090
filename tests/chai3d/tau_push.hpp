#pragma once
// Paper 001's push (8-15 N into the wall) for the simulated TAU: a stiff hand spring (1500 N/m) led
// 10 mm below the surface, saturating at 12 N, with the wall mode under test.
#include "uhaptics/chai3d/CTauDevice.hpp"

inline uhaptics::DeviceSelection tauPushSelection(chai3d::cTauDevice::cWallMode mode) {
  uhaptics::DeviceSelection s;
  s.device = "tau";
  s.hand.waypoints = {uhaptics::Vec3(0, 0, 0.2), uhaptics::Vec3(0, 0, -0.6)};
  s.hand.lap_time = 2.0;
  s.hand.stiffness = 1500.0;
  s.hand.damping = 20.0;
  s.hand.max_force = 12.0;
  s.options["wall"] = mode;
  return s;
}
