// uhaptics-tau-design: designs the LQR wall gains for a TAU
// parameter file at an operating pose and writes them to a JSON file. Default weights: tuned for our
// assumed plant (README, TAU section); --weights 1 1e3 1e7 1 gives paper 001's.
//   uhaptics-tau-design [--params tau.json] [--pose x y z a b g] [--weights v p i r] [--out gains.json]
#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <string>
#include <vector>

#include "uhaptics/backends/params_location.hpp"
#include "uhaptics/core/fault.hpp"
#include "uhaptics/renderers/tau_wall_design.hpp"
#include "uhaptics/tools/cli.hpp"
#include "uhaptics/tools/plot.hpp"

using namespace uhaptics;

namespace {
template <typename M>
void writeMatrix(std::ostream& os, const char* name, const M& m, bool last = false) {
  os << "  \"" << name << "\": [";
  for (Eigen::Index i = 0; i < m.rows(); ++i) {
    os << (i ? ",\n    [" : "\n    [");
    for (Eigen::Index j = 0; j < m.cols(); ++j) os << (j ? ", " : "") << m(i, j);
    os << "]";
  }
  os << "]" << (last ? "\n" : ",\n");
}
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Design LQR position-control wall gains for a TAU-class device (paper 001)"};
  std::string params = defaultParamsDirectory() + "/tau.json";
  std::string out = "out/tau-design/gains.json";
  std::vector<double> pose(6, 0.0);
  const LqrWallWeights defaults;  // tuned for tau.json (README); paper 001: 1 1e3 1e7 1
  std::vector<double> weights = {defaults.velocity, defaults.position, defaults.integral, defaults.torque};
  app.footer("Exit status: 0 gains written; 2 the design could not be made (bad parameter file, a pose outside "
             "its workspace, I/O error); 101/105 a refused command-line value.");
  tools::CommandLine cli(app, "uhaptics-tau-design");
  cli.inputFile("--params", params, "device parameter file");
  bool pose_given = false;
  cli.numbers("--pose", pose, 6,
              "operating pose x y z (m) alpha beta gamma (rad), inside the parameter file's workspace (default: its "
              "home pose)", -1.0, 1.0);
  cli.numbers("--weights", weights, 4, "Q weights on velocity, position, integral; R weight", 1e-9, 1e12);
  cli.outputFile("--out", out, "output JSON file");
  if (const int status = cli.parse(argc, argv); status >= 0) return status;
  pose_given = app.count("--pose") > 0;
  try {
    const TauModel model = TauModel::load(params);
    if (!pose_given) Eigen::Map<Vec6>(pose.data()) = model.homePose();
    // The workspace of the parameter file: a cube of half side h about the home position and
    // +-half angle about each axis.
    const Vec6 offset = Eigen::Map<const Vec6>(pose.data()) - model.homePose();
    const double h = model.workspaceHalfSide(), a = model.workspaceHalfAngle();
    if (offset.head<3>().cwiseAbs().maxCoeff() > h || offset.tail<3>().cwiseAbs().maxCoeff() > a) {
      char why[512];
      std::snprintf(why, sizeof why, "--pose: %g %g %g %g %g %g is outside the workspace of %s (position within %g m "
                    "and angles within %g rad of the home pose)", pose[0], pose[1], pose[2], pose[3], pose[4], pose[5],
                    params.c_str(), h, a);
      throw Error(why);
    }
    LqrWallWeights w{weights[0], weights[1], weights[2], weights[3]};
    const Vec6 op = Eigen::Map<const Vec6>(pose.data());
    const auto t0 = std::chrono::steady_clock::now();
    const LqrWallDesign design = designLqrWall(model, op, w);
    const LqrWallGains& g = design.gains;
    const LqrWallDesignReport& report = design.report;
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    const auto slash = out.find_last_of('/');
    if (slash != std::string::npos) tools::ensureDirectory(out.substr(0, slash));
    std::ofstream os(out);
    if (!os) throw Error("cannot write " + out);
    os << std::setprecision(17) << "{\n  \"device\": \"tau\",\n  \"parameters\": \"" << params << "\",\n";
    os << "  \"weights\": {\"velocity\": " << w.velocity << ", \"position\": " << w.position
       << ", \"integral\": " << w.integral << ", \"torque\": " << w.torque << "},\n";
    os << "  \"period\": " << g.period << ",\n  \"fastest_pole_rad_s\": " << report.fastest_pole_rad_s
       << ",\n  \"dare_relative_residual\": " << report.dare_residual << ",\n";
    writeMatrix(os, "operating_pose", report.operating_pose.transpose());
    writeMatrix(os, "operating_joints", report.operating_joints.transpose());
    writeMatrix(os, "operating_torque", g.operating_torque.transpose());
    writeMatrix(os, "Kc", g.Kc);
    writeMatrix(os, "Ki", g.Ki);
    writeMatrix(os, "observer_gain", g.observer.gain, true);
    os << "}\n";
    std::printf("designed in %.2f ms: fastest closed-loop pole %.0f rad/s, DARE residual %.1e (%d doublings) -> %s\n", ms,
                report.fastest_pole_rad_s, report.dare_residual, report.dare_iterations, out.c_str());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "uhaptics-tau-design: %s\n", e.what());
    return tools::CommandLine::kRunError;
  }
}
