#include "uhaptics/tools/progress.hpp"

#include <cstdio>
#include <unistd.h>

namespace uhaptics::tools {

Progress::Progress(std::string label, std::size_t total)
    : label_(std::move(label)),
      total_(total == 0 ? 1 : total),
      start_(std::chrono::steady_clock::now()),
      last_draw_(start_),
      tty_(isatty(fileno(stderr)) != 0) {
  draw(0, false);
}

Progress::~Progress() { finish(); }

double Progress::elapsedSeconds() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

void Progress::advance(std::size_t n) {
  const std::size_t done = done_ += n;
  const auto now = std::chrono::steady_clock::now();
  std::unique_lock<std::mutex> lock(mutex_, std::try_to_lock);
  if (!lock.owns_lock()) return;  // another thread is drawing; never block the workers
  if (tty_ && now - last_draw_ < std::chrono::milliseconds(100) && done < total_) return;
  last_draw_ = now;
  draw(done, false);
}

void Progress::finish() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (finished_) return;
  finished_ = true;
  draw(done_.load(), true);
}

void Progress::draw(std::size_t done, bool final) {
  const double frac = static_cast<double>(done > total_ ? total_ : done) / static_cast<double>(total_);
  const double elapsed = elapsedSeconds();
  const double eta = frac > 0.0 ? elapsed * (1.0 - frac) / frac : 0.0;
  if (tty_) {
    const int width = 30;
    const int filled = static_cast<int>(frac * width);
    std::fprintf(stderr, "\r%-28s [%.*s%*s] %5.1f%%  %6.1f s  eta %5.1f s", label_.c_str(), filled,
                 "##############################", width - filled, "", 100.0 * frac, elapsed, eta);
    if (final) std::fprintf(stderr, "\n");
  } else {
    const int decile = static_cast<int>(frac * 10.0);
    if (decile == last_decile_ && !final) return;
    if (final && decile == last_decile_ && decile == 10) return;
    last_decile_ = decile;
    std::fprintf(stderr, "%s: %3.0f%% (%zu/%zu) %.1f s\n", label_.c_str(), 100.0 * frac, done, total_,
                 elapsed);
  }
  std::fflush(stderr);
}

}  // namespace uhaptics::tools
