// uhaptics-replay: record and replay (Ruffaldi et al., "Standardized evaluation of haptic rendering
// systems", 2006). Runs a CHAI3D program (one of CHAI3D's unchanged examples relinked with the
// uhaptics slot, or a user's own application) headless under a private Xvfb with its scripted hand
// following a hand recording (docs/recording.md), on the chosen device, option set and backend;
// reads the session's statistics and prints the referee's figures (docs/chai3d.md, "The referee").
// With --baseline the same recording runs again with the device's "method_off" options (its
// dropin.json), and the two are printed side by side: a method and its baseline meet the same user.
//
//   uhaptics-replay --program bin/lin-x86_64/uhaptics-chai3d-23-tooth --recording 23-tooth.tau.csv
//                   --device tau --backend sim --baseline --out out/replay
//                   --expect "method.max_true_penetration_mm<=1" --expect "baseline.max_true_penetration_mm>1"
//
// Exit status: 0 every --expect holds; 1 one does not; 2 a run could not be made (the program ended
// early or wrote no statistics in time, no Xvfb, a bad recording or dropin.json); 101/105 a refused
// command-line value.
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "uhaptics/backends/device_definition.hpp"
#include "uhaptics/backends/params_location.hpp"
#include "uhaptics/backends/hand_recording.hpp"
#include "uhaptics/tools/cli.hpp"

extern char** environ;

namespace {

using Json = nlohmann::ordered_json;
using Clock = std::chrono::steady_clock;
constexpr const char* kTool = "uhaptics-replay";

struct RunError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct Expectation {
  std::string text, run, figure, op;  // run: "method" or "baseline"
  double bound = 0.0;
};

// "<method|baseline>.<referee figure><op><number>", op one of <= >= < >.
Expectation parseExpectation(const std::string& text) {
  Expectation e;
  e.text = text;
  const std::size_t dot = text.find('.');
  const std::size_t op = text.find_first_of("<>");
  const auto refuse = [&](const std::string& why) {
    return std::invalid_argument("--expect: '" + text + "' " + why +
                                 " (expected e.g. method.max_true_penetration_mm<=1 or baseline.chatter_N>0.5)");
  };
  if (dot == std::string::npos || op == std::string::npos || op < dot) throw refuse("is not RUN.FIGURE OP NUMBER");
  e.run = text.substr(0, dot);
  if (e.run != "method" && e.run != "baseline") throw refuse("names neither the method nor the baseline");
  e.figure = text.substr(dot + 1, op - dot - 1);
  if (e.figure.empty()) throw refuse("names no figure");
  const bool with_equal = op + 1 < text.size() && text[op + 1] == '=';
  e.op = text.substr(op, with_equal ? 2 : 1);
  const std::string digits = text.substr(op + e.op.size());
  char* end = nullptr;
  e.bound = std::strtod(digits.c_str(), &end);
  if (digits.empty() || end != digits.c_str() + digits.size() || !std::isfinite(e.bound)) {
    throw refuse("has no finite number after " + e.op);
  }
  return e;
}

bool holds(const Expectation& e, double value) {
  if (!std::isfinite(value)) return false;
  if (e.op == "<=") return value <= e.bound;
  if (e.op == ">=") return value >= e.bound;
  if (e.op == "<") return value < e.bound;
  return value > e.bound;
}

// "NAME=VALUE" device options.
std::map<std::string, double> parseOptions(const std::vector<std::string>& items) {
  std::map<std::string, double> options;
  for (const auto& item : items) {
    const std::size_t eq = item.find('=');
    char* end = nullptr;
    const std::string value = eq == std::string::npos ? "" : item.substr(eq + 1);
    const double parsed = std::strtod(value.c_str(), &end);
    if (eq == 0 || eq == std::string::npos || value.empty() || end != value.c_str() + value.size() ||
        !std::isfinite(parsed)) {
      throw std::invalid_argument("--option: '" + item + "' is not NAME=NUMBER (a device option, docs/chai3d.md)");
    }
    options[item.substr(0, eq)] = parsed;
  }
  return options;
}

// The device's dropin.json: --dropin, else <share>/uhaptics/dropin/<device>.json beside the parameter
// folder (the build's, or the installed prefix's: cmake/uhapticsDevices.cmake assembles both).
std::string dropinFile(const std::string& device, const std::string& given) {
  if (!given.empty()) return given;
  const std::filesystem::path path =
      std::filesystem::path(uhaptics::defaultParamsDirectory()).parent_path() / "dropin" / (device + ".json");
  if (std::filesystem::is_regular_file(path)) return path.string();
  throw RunError("no drop-in rules for device '" + device + "' at " + path.string() + ": name its dropin.json with --dropin");
}

// The baseline's options: the device's dropin.json "method_off".
std::map<std::string, double> methodOff(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw RunError(path + ": cannot read");
  Json dropin;
  try {
    dropin = Json::parse(in);
  } catch (const std::exception& e) {
    throw RunError(path + ": not JSON: " + e.what());
  }
  const auto off = dropin.find("method_off");
  if (off == dropin.end() || !off->is_object() || off->empty()) {
    throw RunError(path + ": no \"method_off\" options: this device states no baseline");
  }
  std::map<std::string, double> options;
  for (const auto& [name, value] : off->items()) {
    if (!value.is_number()) throw RunError(path + ": method_off/" + name + " is not a number");
    options[name] = value.get<double>();
  }
  return options;
}

// A private X server (Xvfb picks a free display number and writes it to a pipe).
class Xvfb {
 public:
  Xvfb() {
    int fds[2];
    if (pipe(fds) != 0) throw RunError("cannot make a pipe for Xvfb");
    pid_ = fork();
    if (pid_ < 0) throw RunError("cannot start Xvfb (fork failed)");
    if (pid_ == 0) {
      close(fds[0]);
      const int null = open("/dev/null", O_RDWR);
      dup2(null, 1);
      dup2(null, 2);
      const std::string fd = std::to_string(fds[1]);
      execlp("Xvfb", "Xvfb", "-displayfd", fd.c_str(), "-screen", "0", "1280x960x24", "-nolisten", "tcp",
             static_cast<char*>(nullptr));
      _exit(127);
    }
    close(fds[1]);
    std::string number;
    const auto deadline = Clock::now() + std::chrono::seconds(20);
    while (number.find('\n') == std::string::npos && Clock::now() < deadline) {
      pollfd p{fds[0], POLLIN, 0};
      if (poll(&p, 1, 200) <= 0) continue;
      char chunk[16];
      const ssize_t n = read(fds[0], chunk, sizeof chunk);
      if (n <= 0) break;
      number.append(chunk, static_cast<std::size_t>(n));
    }
    close(fds[0]);
    number.erase(number.find_last_not_of(" \n") + 1);
    if (number.empty()) {
      stop();
      throw RunError("Xvfb did not start (is it installed? apt-get install xvfb), or run with --no-xvfb");
    }
    display_ = ":" + number;
  }
  ~Xvfb() { stop(); }
  Xvfb(const Xvfb&) = delete;
  Xvfb& operator=(const Xvfb&) = delete;
  const std::string& display() const { return display_; }

 private:
  void stop() {
    if (pid_ <= 0) return;
    kill(pid_, SIGTERM);
    waitpid(pid_, nullptr, 0);
    pid_ = -1;
  }
  pid_t pid_ = -1;
  std::string display_;
};

std::optional<Json> readStats(const std::string& path) {
  std::ifstream in(path);
  if (!in) return std::nullopt;
  try {
    return Json::parse(in);
  } catch (const std::exception&) {
    return std::nullopt;  // written atomically, so only a file another program left
  }
}

double number(const Json& object, const std::string& key) {
  const auto it = object.find(key);
  return it != object.end() && it->is_number() ? it->get<double>() : std::nan("");
}

// The session time the statistics cover: the referee's (simulated) seconds, else the session's.
double sessionSeconds(const Json& stats) {
  const auto referee = stats.find("referee");
  if (referee != stats.end() && referee->is_object()) return number(*referee, "seconds");
  return number(stats, "seconds");
}

std::string tail(const std::string& path, std::size_t lines) {
  std::ifstream in(path);
  std::vector<std::string> all;
  for (std::string line; std::getline(in, line);) all.push_back(line);
  std::string out;
  for (std::size_t i = all.size() > lines ? all.size() - lines : 0; i < all.size(); ++i) out += "    " + all[i] + "\n";
  return out;
}

struct RunSetup {
  std::string program, recording, device, backend, out, display;
  double duration = 0.0, startup = 30.0;
};

// One session of the program on the recording; its final statistics.
Json runOnce(const RunSetup& s, const std::string& tag, const std::map<std::string, double>& options) {
  namespace fs = std::filesystem;
  const std::string stats_path = (fs::path(s.out) / (tag + ".json")).string();
  const std::string config_path = (fs::path(s.out) / (tag + ".config.json")).string();
  const std::string log_path = (fs::path(s.out) / (tag + ".log")).string();
  fs::remove(stats_path);
  Json config = {{"device", "chai3d-selection"},
                 {"format_version", 1},
                 {"selection", {{"device", s.device}, {"backend", s.backend}}},
                 {"stats", stats_path},
                 {"hand", {{"enabled", 1}, {"recording", s.recording}}}};
  if (!options.empty()) config["options"][s.device] = options;
  {
    std::ofstream f(config_path);
    if (!(f << config.dump(1) << "\n")) throw RunError(config_path + ": cannot write");
  }

  // The child's environment: the caller's, less what would override the configuration file.
  std::vector<std::string> env;
  for (char** e = environ; *e != nullptr; ++e) {
    const std::string entry = *e;
    const std::string name = entry.substr(0, entry.find('='));
    if (name.rfind("UHAPTICS_", 0) == 0 || (!s.display.empty() && name == "DISPLAY")) continue;
    env.push_back(entry);
  }
  env.push_back("UHAPTICS_CONFIG=" + config_path);
  if (!s.display.empty()) env.push_back("DISPLAY=" + s.display);
  // Mesa's software renderer spreads each frame over every core: one leaves the other to the
  // device's haptic and servo threads.
  if (std::getenv("LP_NUM_THREADS") == nullptr) env.push_back("LP_NUM_THREADS=1");
  std::vector<char*> envp;
  for (auto& e : env) envp.push_back(e.data());
  envp.push_back(nullptr);

  const pid_t child = fork();
  if (child < 0) throw RunError("cannot start " + s.program + " (fork failed)");
  if (child == 0) {
    const int log = open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (log >= 0) {
      dup2(log, 1);
      dup2(log, 2);
    }
    if (chdir(s.out.c_str()) != 0) _exit(126);
    std::string program = s.program;
    char* argv[] = {program.data(), nullptr};
    execve(program.c_str(), argv, envp.data());
    _exit(127);
  }

  std::cout << kTool << ": " << tag << ": running " << fs::path(s.program).filename().string() << " with "
            << s.device << " on " << s.backend << std::endl;
  const auto deadline = Clock::now() + std::chrono::duration<double>(s.duration + s.startup);
  std::optional<Json> stats;
  int status = 0;
  bool ended = false;
  std::string problem;
  for (;;) {
    if (waitpid(child, &status, WNOHANG) == child) {
      ended = true;
      problem = "the program ended (" +
                (WIFEXITED(status) ? "exit " + std::to_string(WEXITSTATUS(status))
                                   : "signal " + std::to_string(WTERMSIG(status))) +
                ") before its session covered the recording";
      break;
    }
    stats = readStats(stats_path);
    if (stats && sessionSeconds(*stats) >= s.duration) break;
    if (Clock::now() > deadline) {
      const double covered = stats ? sessionSeconds(*stats) : 0.0;
      std::ostringstream why;
      why << "the session covered " << (std::isfinite(covered) ? covered : 0.0) << " s of the recording's "
          << s.duration << " s within " << s.duration + s.startup << " s"
          << (stats ? "" : " (no statistics written: did the program open the device?)");
      problem = why.str();
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  if (!ended) {
    // CHAI3D's examples run until a key is pressed: end it. Its statistics are the periodic file.
    kill(child, SIGTERM);
    const auto grace = Clock::now() + std::chrono::seconds(10);
    while (waitpid(child, &status, WNOHANG) != child) {
      if (Clock::now() > grace) {
        kill(child, SIGKILL);
        waitpid(child, &status, 0);
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
  }
  if (!problem.empty()) throw RunError(tag + ": " + problem + "; its output (" + log_path + "), last lines:\n" + tail(log_path, 15));
  if (stats->value("device", "") != s.device || stats->value("backend", "") != s.backend) {
    throw RunError(tag + ": the statistics are from " + stats->value("device", "?") + " on " +
                   stats->value("backend", "?") + ", not " + s.device + " on " + s.backend);
  }
  const auto referee = stats->find("referee");
  if (referee == stats->end() || !referee->is_object()) {
    throw RunError(tag + ": the statistics have no referee (is the option referee 0?)");
  }
  return *stats;
}

std::string cell(double v) {
  if (!std::isfinite(v)) return "-";
  std::ostringstream os;
  os << std::setprecision(4) << v;
  return os.str();
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Replay a hand recording on a device in a CHAI3D program and print the referee's figures, "
               "optionally beside the device's baseline (its dropin.json method_off) on the same recording"};
  std::string program, recording_path, device, backend = "sim", out = "replay-out", dropin;
  std::vector<std::string> option_items, expect_items;
  bool baseline = false, no_xvfb = false;
  double startup = 30.0;
  app.footer(
      "Exit status: 0 every --expect holds; 1 one does not; 2 a run could not be made; 101/105 a refused "
      "command-line value.");
  uhaptics::tools::CommandLine cli(app, kTool);
  // Required, checked after parsing (CLI11's required() would refuse --list-options too).
  cli.inputFile("--program", program, "The CHAI3D program to run (linked with the uhaptics slot; required)");
  cli.inputFile("--recording", recording_path, "Hand recording (docs/recording.md) the scripted hand follows (required)");
  cli.text("--device", device, "Device (UHAPTICS_DEVICE), required: one of " + uhaptics::deviceNameList());
  cli.choice("--backend", backend, "Backend", {"sim", "emulated"})->capture_default_str();
  cli.texts("--option", option_items, "Device option NAME=VALUE for both runs (repeatable; docs/chai3d.md)");
  app.add_flag("--baseline", baseline, "Also run the device's baseline (its dropin.json method_off) on the recording");
  cli.inputFile("--dropin", dropin, "The device's dropin.json (default: <share>/uhaptics/dropin/<device>.json beside the parameter folder)");
  cli.outputFolder("--out", out, "Folder for the runs' statistics, configurations, logs and replay.csv")
      ->capture_default_str();
  cli.texts("--expect", expect_items,
            "A check RUN.FIGURE OP NUMBER on a referee figure, RUN method or baseline, OP <= >= < > "
            "(repeatable), e.g. method.max_true_penetration_mm<=1");
  cli.number("--startup-timeout", startup, "Seconds the program may take beyond the recording's length", 1.0, 600.0)
      ->capture_default_str();
  app.add_flag("--no-xvfb", no_xvfb, "Run the program on the caller's DISPLAY (or none) instead of a private Xvfb");
  if (const int status = cli.parse(argc, argv); status >= 0) return status;

  std::vector<Expectation> expectations;
  std::map<std::string, double> options;
  uhaptics::HandRecording recording;
  try {
    for (const auto& [name, value] : {std::pair<const char*, const std::string*>{"--program", &program},
                                      {"--recording", &recording_path}, {"--device", &device}}) {
      if (value->empty()) throw std::invalid_argument(std::string(name) + " is required (see --help)");
    }
    static_cast<void>(uhaptics::findDevice(device));  // throws with the registered names
    for (const auto& e : expect_items) expectations.push_back(parseExpectation(e));
    for (const auto& e : expectations) {
      if (e.run == "baseline" && !baseline) throw std::invalid_argument("--expect: '" + e.text + "' needs --baseline");
    }
    options = parseOptions(option_items);
    recording = uhaptics::readHandRecording(recording_path);
  } catch (const std::exception& e) {
    std::cerr << kTool << ": " << e.what() << "\n";
    return uhaptics::tools::CommandLine::kRunError;
  }

  try {
    std::map<std::string, double> off;
    if (baseline) off = methodOff(dropinFile(device, dropin));
    std::filesystem::create_directories(out);
    RunSetup setup;
    setup.program = std::filesystem::absolute(program).string();
    setup.recording = std::filesystem::absolute(recording_path).string();
    setup.device = device;
    setup.backend = backend;
    setup.out = std::filesystem::absolute(out).string();
    setup.duration = recording.duration();
    setup.startup = startup;
    std::optional<Xvfb> xvfb;
    if (!no_xvfb) {
      xvfb.emplace();
      setup.display = xvfb->display();
    }
    std::cout << kTool << ": " << recording_path << ": " << recording.samples.size() << " rows, "
              << recording.duration() << " s, recorded with " << (recording.device.empty() ? "?" : recording.device)
              << " on " << (recording.backend.empty() ? "?" : recording.backend) << " (workspace radius "
              << recording.workspace_radius * 1e3 << " mm)\n";
    std::map<std::string, Json> runs;
    runs["method"] = runOnce(setup, "method", options);
    std::string off_text;
    if (baseline) {
      std::map<std::string, double> with_off = options;
      for (const auto& [name, value] : off) {
        with_off[name] = value;
        off_text += (off_text.empty() ? "" : ", ") + name + " " + cell(value);
      }
      runs["baseline"] = runOnce(setup, "baseline", with_off);
    }

    // The referee's figures, method beside baseline, in the statistics' order.
    const Json& method_referee = runs["method"]["referee"];
    std::ofstream csv(std::filesystem::path(setup.out) / "replay.csv");
    csv << "figure,method" << (baseline ? ",baseline" : "") << "\n";
    std::cout << "\nreferee on " << device << " (" << backend << "), the same recording"
              << (baseline ? "; baseline: " + off_text : "") << "\n";
    std::cout << std::left << std::setw(30) << "figure" << std::right << std::setw(14) << "method"
              << (baseline ? "    baseline" : "") << "\n";
    for (const auto& [name, value] : method_referee.items()) {
      const double m = number(method_referee, name);
      const double b = baseline ? number(runs["baseline"]["referee"], name) : std::nan("");
      std::cout << std::left << std::setw(30) << name << std::right << std::setw(14) << cell(m);
      if (baseline) std::cout << std::setw(12) << cell(b);
      std::cout << "\n";
      csv << name << "," << (std::isfinite(m) ? cell(m) : "") << (baseline ? "," + (std::isfinite(b) ? cell(b) : "") : "")
          << "\n";
    }
    if (!csv) throw RunError(setup.out + "/replay.csv: cannot write");

    int failed = 0;
    for (const auto& e : expectations) {
      const double value = number(runs[e.run]["referee"], e.figure);
      const bool ok = holds(e, value);
      failed += ok ? 0 : 1;
      std::cout << (ok ? "holds: " : "FAILS: ") << e.text << " (" << e.run << "." << e.figure << " = " << cell(value)
                << ")\n";
    }
    return failed == 0 ? uhaptics::tools::CommandLine::kAllPass : uhaptics::tools::CommandLine::kRowsFail;
  } catch (const std::exception& e) {
    std::cerr << kTool << ": " << e.what() << "\n";
    return uhaptics::tools::CommandLine::kRunError;
  }
}
