#pragma once
// Progress display for long runs: a live bar on a terminal, a line every 10 % otherwise (CI logs).
#include <atomic>
#include <chrono>
#include <cstddef>
#include <mutex>
#include <string>

namespace uhaptics::tools {

class Progress {
 public:
  Progress(std::string label, std::size_t total);
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  /// Thread-safe.
  void advance(std::size_t n = 1);
  void finish();
  double elapsedSeconds() const;

 private:
  void draw(std::size_t done, bool final);
  std::string label_;
  std::size_t total_;
  std::atomic<std::size_t> done_{0};
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_draw_;
  std::mutex mutex_;
  bool tty_;
  int last_decile_ = -1;
  bool finished_ = false;
};

}  // namespace uhaptics::tools
