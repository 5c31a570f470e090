#pragma once
// Work sharing for Monte-Carlo studies: indices handed out through an atomic counter, so runs of
// uneven length balance themselves. Each index must be independent (seed per index, not per thread)
// so that results do not depend on the thread count.
#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <mutex>
#include <system_error>
#include <thread>
#include <vector>

namespace uhaptics::experiments {

/// The most worker threads a study starts (the tools' --threads accepts 0..kMaxThreads): far above
/// any core count these studies are run on, far below what exhausts a process's stacks.
constexpr unsigned kMaxThreads = 256;

inline unsigned hardwareThreads() { return std::max(1u, std::thread::hardware_concurrency()); }

/// Calls fn(i) for i in [0, n) on `threads` threads (0 = all cores). Rethrows the first exception.
/// When the system refuses a thread, the work runs on the threads already started (the calling
/// thread at least): the results do not depend on the thread count.
template <typename F>
void parallelFor(std::size_t n, unsigned threads, F&& fn) {
  if (threads == 0) threads = hardwareThreads();
  threads = std::min(threads, kMaxThreads);
  threads = static_cast<unsigned>(std::min<std::size_t>(threads, std::max<std::size_t>(n, 1)));
  std::atomic<std::size_t> next{0};
  std::exception_ptr error;
  std::mutex error_mutex;
  auto worker = [&] {
    for (std::size_t i = next++; i < n; i = next++) {
      try {
        fn(i);
      } catch (...) {
        std::lock_guard<std::mutex> lock(error_mutex);
        if (!error) error = std::current_exception();
        next = n;
      }
    }
  };
  std::vector<std::thread> pool;
  for (unsigned t = 1; t < threads; ++t) {
    try {
      pool.emplace_back(worker);
    } catch (const std::system_error&) {
      break;  // out of threads (or memory for their stacks): carry on with those running
    }
  }
  worker();
  for (auto& t : pool) t.join();
  if (error) std::rethrow_exception(error);
}

}  // namespace uhaptics::experiments
