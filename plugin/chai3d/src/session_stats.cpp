#include "uhaptics/chai3d/session_stats.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "uhaptics/core/fault.hpp"

namespace uhaptics {

void SessionStats::start(double wall_time) noexcept {
  in_contact_ = false;
  in_contact_now_.store(false);
  start_time_.store(wall_time);
  ticks_.store(0);
  contacts_.store(0);
  contact_ticks_.store(0);
  faults_.store(0);
  link_down_ = false;
  ticks_without_reading_.store(0);
  link_losses_.store(0);
  stale_input_ticks_.store(0);
  stale_input_episodes_.store(0);
  input_stale_ = false;
  link_recoveries_.store(0);
  peak_force_.store(0.0);
  peak_output_.store(0.0);
  for (auto& value : figure_values_) value.store(0.0);
  visited_any_.store(false);
}

void SessionStats::recordReading(bool have_reading) noexcept {
  // Single writer: load + store.
  const auto bump = [](std::atomic<std::uint64_t>& c) { c.store(c.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed); };
  if (!have_reading) {
    bump(ticks_without_reading_);
    if (!link_down_) bump(link_losses_);
  } else if (link_down_) {
    bump(link_recoveries_);
  }
  link_down_ = !have_reading;
}

void SessionStats::recordInput(bool stale) noexcept {
  if (stale) {
    stale_input_ticks_.store(stale_input_ticks_.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
    if (!input_stale_)
      stale_input_episodes_.store(stale_input_episodes_.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
  }
  input_stale_ = stale;
}

void SessionStats::recordPosition(double x, double y, double z) noexcept {
  if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z)) return;
  const double p[3] = {x, y, z};
  const bool first = !visited_any_.load(std::memory_order_relaxed);
  for (std::size_t i = 0; i < 3; ++i) {
    if (first || p[i] < visited_min_[i].load(std::memory_order_relaxed)) visited_min_[i].store(p[i], std::memory_order_relaxed);
    if (first || p[i] > visited_max_[i].load(std::memory_order_relaxed)) visited_max_[i].store(p[i], std::memory_order_relaxed);
  }
  // Release: a snapshot that sees the flag sees the first position too.
  if (first) visited_any_.store(true, std::memory_order_release);
}

int SessionStats::declareFigure(const char* name, RendererFigure::Kind kind) {
  for (int i = 0; i < figure_count_; ++i) {
    if (std::string(figures_[static_cast<std::size_t>(i)].name) == name) {
      throw Error(std::string("renderer figure '") + name + "' declared twice");
    }
  }
  if (figure_count_ >= SessionStatsSnapshot::kMaxFigures) {
    throw Error("more than " + std::to_string(SessionStatsSnapshot::kMaxFigures) + " renderer figures");
  }
  RendererFigure& figure = figures_[static_cast<std::size_t>(figure_count_)];
  figure.name = name;
  figure.kind = kind;
  figure_values_[static_cast<std::size_t>(figure_count_)].store(0.0);
  return figure_count_++;
}

void SessionStats::count(int id, std::uint64_t n) noexcept {
  if (id < 0 || id >= figure_count_) return;
  auto& value = figure_values_[static_cast<std::size_t>(id)];
  // Single writer (the servo thread): load + store is exact without a read-modify-write.
  value.store(value.load(std::memory_order_relaxed) + static_cast<double>(n), std::memory_order_relaxed);
}

void SessionStats::observeMaximum(int id, double v) noexcept {
  if (id < 0 || id >= figure_count_ || !std::isfinite(v)) return;
  auto& value = figure_values_[static_cast<std::size_t>(id)];
  if (v > value.load(std::memory_order_relaxed)) value.store(v, std::memory_order_relaxed);
}

void SessionStats::setValue(int id, double v) noexcept {
  if (id < 0 || id >= figure_count_ || !std::isfinite(v)) return;
  figure_values_[static_cast<std::size_t>(id)].store(v, std::memory_order_relaxed);
}

const RendererFigure* SessionStatsSnapshot::figure(const std::string& name) const noexcept {
  for (int i = 0; i < figure_count; ++i) {
    if (name == figures[static_cast<std::size_t>(i)].name) return &figures[static_cast<std::size_t>(i)];
  }
  return nullptr;
}

void SessionStats::recordTick(double commanded_force, double output_magnitude, bool fault) noexcept {
  // Single writer: a plain load and store per counter, no locked read-modify-write. faults_ is
  // also counted by recordFault() from the application's thread: it keeps its atomic add.
  ticks_.store(ticks_.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
  if (fault) faults_.fetch_add(1, std::memory_order_relaxed);
  if (!std::isfinite(commanded_force)) return;  // counted as a fault by the caller
  if (!in_contact_ && commanded_force > threshold_) {
    in_contact_ = true;
    contacts_.store(contacts_.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
  } else if (in_contact_ && commanded_force < 0.5 * threshold_) {
    in_contact_ = false;
  }
  if (in_contact_) contact_ticks_.store(contact_ticks_.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
  in_contact_now_.store(in_contact_, std::memory_order_relaxed);
  // Single writer: plain load/store keeps the maxima exact without a compare-exchange loop.
  if (commanded_force > peak_force_.load(std::memory_order_relaxed)) {
    peak_force_.store(commanded_force, std::memory_order_relaxed);
  }
  if (std::isfinite(output_magnitude) && output_magnitude > peak_output_.load(std::memory_order_relaxed)) {
    peak_output_.store(output_magnitude, std::memory_order_relaxed);
  }
}

SessionStatsSnapshot SessionStats::snapshot(double wall_time) const noexcept {
  SessionStatsSnapshot s;
  s.ticks = ticks_.load();
  s.seconds = std::max(0.0, wall_time - start_time_.load());
  s.rate_hz = s.seconds > 0.0 ? static_cast<double>(s.ticks) / s.seconds : 0.0;
  s.contacts = contacts_.load();
  s.contact_ticks = contact_ticks_.load();
  s.peak_force = peak_force_.load();
  s.peak_output = peak_output_.load();
  s.faults = faults_.load();
  s.in_contact = in_contact_now_.load();
  s.ticks_without_reading = ticks_without_reading_.load();
  s.link_losses = link_losses_.load();
  s.stale_input_ticks = stale_input_ticks_.load();
  s.stale_input_episodes = stale_input_episodes_.load();
  s.link_recoveries = link_recoveries_.load();
  if (visited_any_.load(std::memory_order_acquire)) {
    for (std::size_t i = 0; i < 3; ++i) {
      s.visited_min[i] = visited_min_[i].load();
      s.visited_max[i] = visited_max_[i].load();
    }
  }
  s.figure_count = figure_count_;
  for (int i = 0; i < figure_count_; ++i) {
    const auto k = static_cast<std::size_t>(i);
    s.figures[k] = figures_[k];
    s.figures[k].value = figure_values_[k].load();
  }
  return s;
}

namespace {

// Labels come from our own configuration, but a path or a user-supplied name may contain quotes.
std::string quoted(const std::string& text) {
  std::string out = "\"";
  for (const char c : text) {
    if (c == '"' || c == '\\') out += '\\';
    if (static_cast<unsigned char>(c) >= 0x20) out += c;
  }
  return out + "\"";
}

}  // namespace

std::string formatStatsJson(const SessionStatsSnapshot& stats, const std::string& device,
                            const std::string& backend, const std::string& renderer) {
  std::ostringstream out;
  out.precision(9);
  out << "{\n"
      << "  \"device\": " << quoted(device) << ",\n"
      << "  \"backend\": " << quoted(backend) << ",\n"
      << "  \"renderer\": " << quoted(renderer) << ",\n"
      << "  \"ticks\": " << stats.ticks << ",\n"
      << "  \"seconds\": " << stats.seconds << ",\n"
      << "  \"rate_hz\": " << stats.rate_hz << ",\n"
      << "  \"contacts\": " << stats.contacts << ",\n"
      << "  \"contact_ticks\": " << stats.contact_ticks << ",\n"
      << "  \"peak_force_N\": " << stats.peak_force << ",\n"
      << "  \"peak_output\": " << stats.peak_output << ",\n"
      << "  \"faults\": " << stats.faults << ",\n"
      << "  \"in_contact\": " << (stats.in_contact ? "true" : "false") << ",\n"
      << "  \"ticks_without_reading\": " << stats.ticks_without_reading << ",\n"
      << "  \"link_losses\": " << stats.link_losses << ",\n"
      << "  \"stale_input_ticks\": " << stats.stale_input_ticks << ",\n"
      << "  \"stale_input_episodes\": " << stats.stale_input_episodes << ",\n"
      << "  \"link_recoveries\": " << stats.link_recoveries << ",\n"
      << "  \"visited_min_radii\": [" << stats.visited_min[0] << ", " << stats.visited_min[1] << ", "
      << stats.visited_min[2] << "],\n"
      << "  \"visited_max_radii\": [" << stats.visited_max[0] << ", " << stats.visited_max[1] << ", "
      << stats.visited_max[2] << "],\n"
      << "  \"renderer_figures\": {";
  for (int i = 0; i < stats.figure_count; ++i) {
    const RendererFigure& figure = stats.figures[static_cast<std::size_t>(i)];
    out << (i == 0 ? "\n" : ",\n") << "    " << quoted(figure.name) << ": ";
    if (figure.kind == RendererFigure::Kind::kCount) {
      out << static_cast<std::uint64_t>(figure.value);
    } else {
      out << figure.value;
    }
  }
  out << (stats.figure_count > 0 ? "\n  }" : "}");
  if (stats.has_referee) {
    const RefereeReport& r = stats.referee;
    const auto number = [&out](double v) -> std::ostream& { return std::isfinite(v) ? out << v : out << "null"; };
    out << ",\n  \"referee\": {\n"
        << "    \"samples\": " << r.samples << ",\n"
        << "    \"seconds\": " << r.seconds << ",\n"
        << "    \"contacts\": " << r.contacts << ",\n"
        << "    \"contact_samples\": " << r.contact_samples << ",\n"
        << "    \"hold_samples\": " << r.hold_samples << ",\n"
        << "    \"onset_samples\": " << r.onset_samples << ",\n"
        << "    \"turned_samples\": " << r.turned_samples << ",\n"
        << "    \"max_true_penetration_mm\": ";
    number(r.max_true_penetration_mm) << ",\n    \"rendered_stiffness_N_per_m\": ";
    number(r.rendered_stiffness_N_per_m) << ",\n    \"rate_hardness_N_per_m\": ";
    number(r.rate_hardness_N_per_m) << ",\n    \"force_error_rms_N\": ";
    number(r.force_error_rms_N) << ",\n    \"generated_energy_mJ\": ";
    number(r.generated_energy_mJ) << ",\n    \"chatter_N\": ";
    number(r.chatter_N) << ",\n    \"saturated_share\": ";
    number(r.saturated_share) << ",\n    \"peak_user_force_N\": ";
    number(r.peak_user_force_N) << ",\n    \"peak_applied_force_N\": ";
    number(r.peak_applied_force_N) << "\n  }";
  }
  if (stats.has_servo_timing) {
    const TimingReport& t = stats.servo_timing;
    out << ",\n  \"servo_timing\": {\n"
        << "    \"samples\": " << t.samples << ",\n"
        << "    \"nominal_period_us\": " << t.nominal_period_us << ",\n"
        << "    \"period_p99_us\": " << t.period.p99_us << ",\n"
        << "    \"period_max_us\": " << t.period.max_us << ",\n"
        << "    \"wake_latency_p99_us\": " << t.wake_latency.p99_us << ",\n"
        << "    \"wake_latency_max_us\": " << t.wake_latency.max_us << ",\n"
        << "    \"overruns\": " << t.overruns << ",\n"
        << "    \"missed_periods\": " << t.missed_periods << "\n  }";
  }
  out << "\n}\n";
  return out.str();
}

void writeFileAtomically(const std::string& path, const std::string& text) {
  const std::string temporary = path + ".tmp";
  {
    std::ofstream file(temporary, std::ios::trunc);
    file << text;
    file.flush();
    if (!file) throw Error("cannot write " + temporary);
  }
  if (std::rename(temporary.c_str(), path.c_str()) != 0) {
    std::remove(temporary.c_str());
    throw Error("cannot rename " + temporary + " to " + path);
  }
}

}  // namespace uhaptics
