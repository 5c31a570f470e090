// The papers' published numbers and the checks against them, as the experiments library states them
// (the tools write exactly these tables): measured values at the papers' own numbers pass, values
// past a bound fail, rows that need unpublished data never fail a run.
#include <catch2/catch.hpp>
#include <limits>
#include <string>
#include <vector>

#include "device_models.hpp"
#include "uhaptics/experiments/exo_fig4.hpp"
#include "uhaptics/experiments/rhi_experiments.hpp"
#include "uhaptics/experiments/tau_study.hpp"

using namespace uhaptics;
using experiments::ReproductionTable;

namespace {
// The row whose quantity starts with `prefix` (the first one); fails the test when there is none.
const experiments::ReproductionRow& row(const ReproductionTable& table, const std::string& prefix) {
  for (const auto& r : table.rows())
    if (r.quantity.compare(0, prefix.size(), prefix) == 0) return r;
  FAIL("no row " << prefix);
  throw;  // not reached
}
}  // namespace

TEST_CASE("TAU study: paper 001's checks pass at its published numbers and fail past their bounds") {
  const TauModel& model = test::tauModel();
  LqrWallDesign design;
  design.report.fastest_pole_rad_s = 2480.0;
  study::Requirements req;
  req.step = {1.0, 0.02, 0.05};  // overshoot %, rise time s, settling time s
  req.deviation = 5e-4;
  req.deviation_encoders = 1e-3;
  study::GridStudy grid;  // Table IV: variants 0 lqr_s1, 1 spring_s1, 2 lqr_s2, 3 spring_s2
  grid.lowest_k_z1[0] = 17174.0;
  grid.highest_k_z1[1] = 3112.6;
  grid.lowest_k_zs[0] = 92387.0;
  grid.highest_k_zs[1] = 6180.5;
  grid.lowest_k_zs[2] = 65002.0;
  grid.highest_k_zs[3] = 6202.1;
  grid.max_penetration = {0.9e-3, 2e-3, 0.5e-3, 2e-3, 1.05e-3, 0.3e-3};
  grid.delay_runs = 90;
  grid.delay_runs_over_1mm = 3;  // CoS-D: 3 of 90
  grid.delay_max_of_90_quantile = 1.05e-3;
  grid.referee_max_penetration = {0.9e-3, 2.6e-3, 0.5e-3, 5.5e-3, 1.2e-3, 0.4e-3};
  const ReproductionTable pass = study::reproductionTable(model, design, req, grid);
  CHECK(pass.rows().size() == 16);
  for (const auto& r : pass.rows()) {
    INFO(r.quantity);
    CHECK(r.pass);
    CHECK(r.paper == "001");
  }
  CHECK(row(pass, "sc.1 lowest K_z1, LQR").published == 17174.0);

  design.report.fastest_pole_rad_s = 2480.0 * 1.11;
  grid.max_penetration[2] = 1e-3;
  grid.delay_runs_over_1mm = 4;
  grid.delay_max_of_90_quantile = 1.1e-3;
  grid.referee_max_penetration[1] = grid.referee_max_penetration[3] = 1.7e-3;  // the LQR's 0.9 mm: over half
  grid.highest_k_zs[3] = 6600.0;  // 65002 < 10 x 6600
  req.deviation_encoders = 1e-3 + model.encoderResolution();
  const ReproductionTable fail = study::reproductionTable(model, design, req, grid);
  CHECK(row(fail, "fastest closed-loop pole").fails());
  CHECK(row(fail, "max penetration, LQR").fails());
  CHECK(row(fail, "runs above 1 mm").fails());
  CHECK(row(fail, "penetration, LQR, delay 0-3").fails());
  CHECK(row(fail, "referee: max true penetration").fails());
  CHECK(row(fail, "sc.2 lowest K_zs, LQR").fails());
  CHECK(row(fail, "15 N force step, observer on the encoders").fails());
  CHECK_FALSE(row(fail, "sc.1 lowest K_zs, LQR").fails());
}

TEST_CASE("TAU study: run seeds and per-point statistics") {
  CHECK(study::runSeed(2021, 5) == study::runSeed(2021, 5));
  CHECK(study::runSeed(2021, 5) != study::runSeed(2021, 6));
  CHECK(study::runSeed(2021, 5) != study::runSeed(2022, 5));
  const study::Statistics s = study::statistics({1.0, 2.0, 3.0});
  CHECK(s.mean == 2.0);
  CHECK(s.stddev == Approx(1.0));
  CHECK(s.min == 1.0);
  CHECK(s.max == 3.0);
  CHECK(study::statistics({4.0}).stddev == 0.0);
  CHECK(study::studyVariants().size() == study::kNumVariants);
  CHECK(std::string(study::studyVariants()[4].label) == "lqr_s1_delay");
}

namespace {
rhi::Studies paper003Studies() {
  rhi::Studies s;
  s.home = {123.0, 3.3};
  s.example.K = 5.0 * 5.8;
  s.example.zeta = 2.6 / 5.0;
  const double peak[3] = {3.0, 2.5, 3.5};
  for (std::size_t c = 0; c < 3; ++c) {
    s.example.configs[c].q.setZero();
    s.example.configs[c].peak_force = peak[c];
    s.example.configs[c].min_alpha = c == 2 ? 1.0 : 0.8;
  }
  auto palpation = [](const char* name, double peak_force, double inertia, double friction) {
    rhi::PalpationCase c;
    c.name = name;
    c.q_settled.setZero();
    c.limit_distance = 0.1;
    c.peak_force = peak_force;
    c.inertia_model = c.inertia_identified = inertia;
    c.friction_reference = c.friction_identified = friction;
    c.coulomb_reference = c.coulomb_identified = 0.1;
    c.fit_valid = true;
    return c;
  };
  s.free_case = palpation("free", 5.674, 0.036, 0.295);  // Table I
  s.stiff_case = palpation("stiff", 8.564, 0.125, 0.633);
  s.workspace.valid = s.workspace.above = 100;
  s.workspace.min_ratio = 1.2;
  s.workspace.max_ratio = 3.0;
  s.smooth.transition_duration = s.abrupt.transition_duration = 0.5;
  s.smooth.max_null_torque_jump = 0.1;
  s.abrupt.max_null_torque_jump = 1.0;
  return s;
}
}  // namespace

TEST_CASE("RHI studies: paper 003's checks pass at its published numbers, Table I's force rows need data") {
  rhi::Studies s = paper003Studies();
  const ReproductionTable pass = rhi::reproductionTable(s);
  CHECK(pass.rows().size() == 22);
  for (const auto& r : pass.rows()) {
    INFO(r.quantity);
    CHECK(r.pass);
  }
  CHECK(rhi::summary(s).find("(paper: +51 %)") != std::string::npos);

  s.home.K = 123.6;                       // outside the paper's rounding
  s.stiff_case.peak_force = 6.0;          // needs the unpublished base frame
  s.workspace.unexplained = 1;
  s.smooth.max_null_torque_jump = 0.5;    // not below half the abrupt jump
  const ReproductionTable fail = rhi::reproductionTable(s);
  CHECK(row(fail, "K = mu lambda_max").fails());
  const auto& stiff = row(fail, "Table I: max force along u, stiff ellipsoid");
  CHECK_FALSE(stiff.pass);
  CHECK_FALSE(stiff.fails());
  CHECK_FALSE(row(fail, "Table I: force capability gain").fails());
  CHECK(row(fail, "Fig. 10: ratio > 1 wherever").fails());
  CHECK(row(fail, "Fig. 11: null-space torque jump").fails());
}

TEST_CASE("RHI studies: the workspace summary counts the map's kinds") {
  std::vector<rhi::WorkspacePoint> map(4);
  for (auto& p : map) p.rematched = false;
  map[0].ratio = 1.5;
  map[0].kind = rhi::RatioKind::kAbove;
  map[0].rematched = true;
  map[1].ratio = 0.9;
  map[1].kind = rhi::RatioKind::kPinnedAtSameStop;
  map[2].ratio = 0.8;
  map[2].kind = rhi::RatioKind::kUnexplained;
  map[3].ratio = std::numeric_limits<double>::quiet_NaN();  // unreachable
  const rhi::WorkspaceSummary w = rhi::summarize(map);
  CHECK(w.valid == 3);
  CHECK(w.above == 1);
  CHECK(w.pinned == 1);
  CHECK(w.unexplained == 1);
  CHECK(w.rematched == 1);
  CHECK(w.lifted == 1);
  CHECK(w.min_ratio == 0.8);
  CHECK(w.max_ratio == 1.5);
}

TEST_CASE("Exo Fig. 4: paper 000's checks pass when the subspace proxy is passive and the others are not always") {
  exo::Fig4Study study;
  study.options.zq = 1.0;
  study.contact_amplitude_deg = 5.0;
  for (auto* r : {&study.protocol, &study.contact})
    for (auto& s : r->summary) s = {10, 10, 10, 10, 0, 1.0, -1.0, -1.0, -1.0};
  for (int m : {exo::kStandard, exo::kNullSpace}) study.protocol.summary[m].fd_passive = 9;
  const ReproductionTable pass = exo::reproductionTable(study);
  CHECK(pass.rows().size() == 9);
  for (const auto& r : pass.rows()) {
    INFO(r.quantity);
    CHECK(r.pass);
  }
  row(pass, "subspace (eq. 8, linearized) passive by finite differences, finger within 5 deg");

  study.protocol.summary[exo::kSubspaceNonlinear].fd_passive = 9;
  study.protocol.summary[exo::kStandard].fd_passive = 10;
  study.protocol.max_subspace_theory_error = 1e-6;
  const ReproductionTable fail = exo::reproductionTable(study);
  CHECK(row(fail, "subspace (eq. 6, nonlinear) passive by finite differences").fails());
  CHECK(row(fail, "standard passive by finite differences").fails());
  CHECK(row(fail, "subspace d tau_a/d q_a in theory").fails());
}
