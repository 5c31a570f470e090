#pragma once
// Timing statistics of a periodic thread, written by that thread and readable at any time from
// others: 1 us histograms of the measured period and of the wake-up latency (how late the thread
// woke after its deadline: the jitter a device sees), plus overrun counts. Recording is wait-free
// and allocation-free (relaxed atomics; a concurrent reader sees a consistent-enough snapshot for
// statistics, never a torn counter).
#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <string>

namespace uhaptics {

struct Percentiles {
  double p50_us = 0, p90_us = 0, p99_us = 0, p999_us = 0, max_us = 0, mean_us = 0;
};

struct TimingReport {
  std::uint64_t samples = 0;
  double nominal_period_us = 0;
  Percentiles period;
  Percentiles wake_latency;   // jitter: actual wake-up minus deadline
  std::uint64_t overruns = 0;        // cycles that woke a full period or more late
  std::uint64_t missed_periods = 0;  // deadlines skipped because of overruns
  std::string format() const;        // one block of text for logs and docs/hardware.md
};

class TimingStats {
 public:
  static constexpr int kBins = 20000;  // 1 us bins up to 20 ms; longer goes into the last bin

  explicit TimingStats(double nominal_period_us);
  void record(std::int64_t period_ns, std::int64_t latency_ns, std::uint64_t missed) noexcept;
  void reset() noexcept;
  TimingReport report() const;
  /// Copies the two histograms (kBins counts each, bin b = [b, b+1) us) for figures.
  void histograms(std::uint32_t* period, std::uint32_t* latency) const noexcept;

 private:
  struct Histogram {
    std::array<std::atomic<std::uint32_t>, kBins> bins{};
    std::atomic<std::uint64_t> count{0}, max_ns{0}, sum_ns{0};
    void add(std::int64_t ns) noexcept;
    Percentiles percentiles() const;
  };
  double nominal_period_us_;
  std::unique_ptr<Histogram> period_, latency_;  // 80 kB each: on the heap, allocated once here
  std::atomic<std::uint64_t> overruns_{0}, missed_{0};
};

}  // namespace uhaptics
