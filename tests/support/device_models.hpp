#pragma once
// The devices' models from the shipped parameter files, loaded once per test program (the models
// are immutable, so every test file of a suite shares the same instance).
#include "params.hpp"
#include "uhaptics/models/exo_finger_model.hpp"
#include "uhaptics/models/planar_linkage_model.hpp"
#include "uhaptics/models/tau_model.hpp"

namespace uhaptics::test {

/// devices/tau/params/tau.json.
inline const TauModel& tauModel() {
  static const TauModel m = TauModel::load(paramsPath("tau.json"));
  return m;
}

/// devices/params/exo_finger.json: paper 000's finger exoskeleton.
inline const ExoFingerModel& exoModel() {
  static const ExoFingerModel m = ExoFingerModel::load(paramsPath("exo_finger.json"));
  return m;
}

/// devices/rhi/params/rhi4.json: paper 003's 4-DoF redundant interface.
inline const Rhi4Model& rhi4Model() {
  static const Rhi4Model m = Rhi4Model::load(paramsPath("rhi4.json"), "rhi4");
  return m;
}

/// devices/planar3/params/planar3.json: paper 003's 3-DoF example arm.
inline const Planar3Model& planar3Model() {
  static const Planar3Model m = Planar3Model::load(paramsPath("planar3.json"), "planar3");
  return m;
}

}  // namespace uhaptics::test
