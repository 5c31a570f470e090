#include "uhaptics/backends/hand_recording.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <istream>
#include <sstream>

#include "uhaptics/core/fault.hpp"

namespace uhaptics {
namespace {

constexpr const char* kTitle = "# uhaptics hand recording";
// The columns in their order; docs/recording.md says what each is.
constexpr const char* kColumns[] = {"time_s",
                                    "anchor_x",
                                    "anchor_y",
                                    "anchor_z",
                                    "anchor_vx",
                                    "anchor_vy",
                                    "anchor_vz",
                                    "grip_stiffness_N_per_m",
                                    "grip_damping_N_s_per_m",
                                    "grip_max_force_N",
                                    "scene_fx_N",
                                    "scene_fy_N",
                                    "scene_fz_N",
                                    "scene_x",
                                    "scene_y",
                                    "scene_z"};
constexpr std::size_t kColumnCount = sizeof(kColumns) / sizeof(kColumns[0]);

std::string header() {
  std::string line;
  for (const char* c : kColumns) line += (line.empty() ? "" : ",") + std::string(c);
  return line;
}

[[noreturn]] void refuse(const std::string& origin, std::size_t line, const std::string& field, const std::string& what) {
  throw Error(origin + ":" + std::to_string(line) + ": " + field + ": " + what);
}

double number(const std::string& text, const std::string& origin, std::size_t line, const std::string& field) {
  const char* begin = text.c_str();
  char* end = nullptr;
  const double value = std::strtod(begin, &end);
  if (text.empty() || end != begin + text.size()) refuse(origin, line, field, "'" + text + "' is not a number");
  if (!std::isfinite(value)) refuse(origin, line, field, "'" + text + "' is not finite");
  return value;
}

void requireWithin(double value, double lo, double hi, const std::string& origin, std::size_t line,
                   const std::string& field) {
  if (value < lo || value > hi) {
    std::ostringstream range;
    range << value << " is outside [" << lo << ", " << hi << "]";
    refuse(origin, line, field, range.str());
  }
}

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> fields;
  std::size_t start = 0;
  for (;;) {
    const std::size_t comma = line.find(',', start);
    fields.push_back(line.substr(start, comma == std::string::npos ? std::string::npos : comma - start));
    if (comma == std::string::npos) return fields;
    start = comma + 1;
  }
}

HandSample parseRow(const std::string& line, std::size_t number_of_line, const std::string& origin) {
  const std::vector<std::string> fields = split(line);
  if (fields.size() != kColumnCount) {
    refuse(origin, number_of_line, "row", std::to_string(fields.size()) + " fields where the header has " +
                                              std::to_string(kColumnCount));
  }
  double v[kColumnCount];
  for (std::size_t i = 0; i < kColumnCount; ++i) v[i] = number(fields[i], origin, number_of_line, kColumns[i]);
  HandSample s;
  s.time = v[0];
  s.anchor = Vec3(v[1], v[2], v[3]);
  s.anchor_velocity = Vec3(v[4], v[5], v[6]);
  s.stiffness = v[7];
  s.damping = v[8];
  s.max_force = v[9];
  s.scene_force = Vec3(v[10], v[11], v[12]);
  s.scene_position = Vec3(v[13], v[14], v[15]);
  using L = HandGripLimits;
  requireWithin(s.time, 0.0, 1e6, origin, number_of_line, kColumns[0]);
  if (s.anchor.norm() > L::kMaxAnchorRadii * (1.0 + 1e-6)) {  // the slack: rows rounded to 7 digits
    refuse(origin, number_of_line, "anchor", "more than " + std::to_string(L::kMaxAnchorRadii) +
                                                 " workspace radii from the centre");
  }
  requireWithin(s.stiffness, L::kMinStiffness, L::kMaxStiffness, origin, number_of_line, kColumns[7]);
  requireWithin(s.damping, 0.0, L::kMaxDamping, origin, number_of_line, kColumns[8]);
  requireWithin(s.max_force, L::kMinForce, L::kMaxForce, origin, number_of_line, kColumns[9]);
  return s;
}

}  // namespace

HandRecording parseHandRecording(std::istream& in, const std::string& origin) {
  HandRecording recording;
  std::string line;
  std::size_t line_number = 0;
  bool titled = false, versioned = false, columns = false;
  while (std::getline(in, line)) {
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.pop_back();  // a file saved with CRLF line ends
    if (!titled) {
      if (line != kTitle) refuse(origin, line_number, "header", "the first line must be '" + std::string(kTitle) + "'");
      titled = true;
      continue;
    }
    if (!columns && line.rfind("#", 0) == 0) {
      // "# key: value" metadata; other comment lines are left alone.
      const std::size_t colon = line.find(':');
      if (colon == std::string::npos) continue;
      std::string key = line.substr(1, colon - 1), value = line.substr(colon + 1);
      key.erase(0, key.find_first_not_of(' '));
      value.erase(0, value.find_first_not_of(' '));
      if (key == "format_version") {
        if (value != std::to_string(HandRecording::kFormatVersion)) {
          refuse(origin, line_number, "format_version", "'" + value + "' is not a version this build reads (" +
                                                            std::to_string(HandRecording::kFormatVersion) + ")");
        }
        versioned = true;
      } else if (key == "workspace_radius_m") {
        recording.workspace_radius = number(value, origin, line_number, key);
        requireWithin(recording.workspace_radius, 1e-4, 10.0, origin, line_number, key);
      } else if (key == "device") {
        recording.device = value;
      } else if (key == "backend") {
        recording.backend = value;
      } else if (key == "dropped_rows") {
        const double dropped = number(value, origin, line_number, key);
        requireWithin(dropped, 0.0, 1e12, origin, line_number, key);
        recording.dropped_rows = static_cast<std::size_t>(dropped);
      }
      continue;
    }
    if (!columns) {
      if (!versioned) refuse(origin, line_number, "format_version", "missing before the column header");
      if (!(recording.workspace_radius > 0.0)) refuse(origin, line_number, "workspace_radius_m", "missing before the column header");
      if (line != header()) refuse(origin, line_number, "columns", "expected '" + header() + "'");
      columns = true;
      continue;
    }
    if (line.empty()) continue;
    HandSample s = parseRow(line, line_number, origin);
    if (!recording.samples.empty() && !(s.time > recording.samples.back().time)) {
      refuse(origin, line_number, kColumns[0], "not after the previous row's time");
    }
    recording.samples.push_back(s);
  }
  if (!titled) refuse(origin, 1, "header", "the file is empty");
  if (!columns) refuse(origin, line_number, "columns", "no column header");
  if (recording.samples.size() < 2) refuse(origin, line_number, "rows", "a recording needs at least two rows");
  return recording;
}

HandRecording readHandRecording(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error(path + ": cannot read the hand recording");
  return parseHandRecording(in, path);
}

std::string formatHandRecording(const HandRecording& recording) {
  std::string text = std::string(kTitle) + "\n# format_version: " + std::to_string(HandRecording::kFormatVersion) + "\n";
  char buffer[512];
  std::snprintf(buffer, sizeof buffer, "# workspace_radius_m: %.9g\n", recording.workspace_radius);
  text += buffer;
  if (!recording.device.empty()) text += "# device: " + recording.device + "\n";
  if (!recording.backend.empty()) text += "# backend: " + recording.backend + "\n";
  text += "# dropped_rows: " + std::to_string(recording.dropped_rows) + "\n";
  text += header() + "\n";
  for (const HandSample& s : recording.samples) {
    // Positions to 1e-7 radii (nanometres on a desktop device), forces to 1 mN and better.
    std::snprintf(buffer, sizeof buffer,
                  "%.9g,%.7g,%.7g,%.7g,%.7g,%.7g,%.7g,%.7g,%.7g,%.7g,%.5g,%.5g,%.5g,%.7g,%.7g,%.7g\n", s.time,
                  s.anchor.x(), s.anchor.y(), s.anchor.z(), s.anchor_velocity.x(), s.anchor_velocity.y(),
                  s.anchor_velocity.z(), s.stiffness, s.damping, s.max_force, s.scene_force.x(), s.scene_force.y(),
                  s.scene_force.z(), s.scene_position.x(), s.scene_position.y(), s.scene_position.z());
    text += buffer;
  }
  return text;
}

HandRecorder::HandRecorder(double period, std::size_t capacity) : period_(period) {
  if (!std::isfinite(period) || period <= 0.0) throw Error("hand recorder: the period must be finite and > 0");
  if (capacity == 0) throw Error("hand recorder: the capacity must be at least one row");
  rows_.resize(capacity);
}

// The slack absorbs the rounding of a servo clock's k * period (0.01 may come out as 0.00999...).
bool HandRecorder::due(double t) const noexcept { return t >= next_due_ - 1e-9; }

void HandRecorder::record(const HandSample& sample) noexcept {
  // Rows land on the period's grid (not one period after a late row), so the rate holds on average.
  next_due_ = (std::floor(sample.time / period_ + 1e-9) + 1.0) * period_;
  const std::size_t n = count_.load(std::memory_order_relaxed);
  if (n == rows_.size()) {
    dropped_.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  rows_[n] = sample;
  count_.store(n + 1, std::memory_order_release);  // the row is complete before a reader sees it
}

void HandRecorder::clear() noexcept {
  count_.store(0, std::memory_order_release);
  dropped_.store(0, std::memory_order_relaxed);
  next_due_ = 0.0;
}

}  // namespace uhaptics
