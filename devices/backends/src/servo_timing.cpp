#include "uhaptics/backends/servo_timing.hpp"

#include <algorithm>
#include <cstdio>

namespace uhaptics {

TimingStats::TimingStats(double nominal_period_us)
    : nominal_period_us_(nominal_period_us),
      period_(std::make_unique<Histogram>()),
      latency_(std::make_unique<Histogram>()) {}

void TimingStats::Histogram::add(std::int64_t ns) noexcept {
  const std::uint64_t v = static_cast<std::uint64_t>(std::max<std::int64_t>(ns, 0));
  const std::size_t bin = std::min<std::uint64_t>(v / 1000, kBins - 1);
  bins[bin].fetch_add(1, std::memory_order_relaxed);
  count.fetch_add(1, std::memory_order_relaxed);
  sum_ns.fetch_add(v, std::memory_order_relaxed);
  if (v > max_ns.load(std::memory_order_relaxed)) max_ns.store(v, std::memory_order_relaxed);  // single writer
}

Percentiles TimingStats::Histogram::percentiles() const {
  Percentiles p;
  const std::uint64_t n = count.load(std::memory_order_relaxed);
  if (n == 0) return p;
  const double fractions[4] = {0.5, 0.9, 0.99, 0.999};
  double* outputs[4] = {&p.p50_us, &p.p90_us, &p.p99_us, &p.p999_us};
  std::uint64_t seen = 0;
  int next = 0;
  for (int b = 0; b < kBins && next < 4; ++b) {
    seen += bins[b].load(std::memory_order_relaxed);
    // Upper edge of the bin: a conservative (never optimistic) percentile, 1 us resolution.
    while (next < 4 && static_cast<double>(seen) >= fractions[next] * static_cast<double>(n))
      *outputs[next++] = b + 1.0;
  }
  p.max_us = static_cast<double>(max_ns.load(std::memory_order_relaxed)) / 1000.0;
  p.mean_us = static_cast<double>(sum_ns.load(std::memory_order_relaxed)) / 1000.0 / static_cast<double>(n);
  for (double* o : outputs) *o = std::min(*o, std::max(p.max_us, 1.0));
  return p;
}

void TimingStats::record(std::int64_t period_ns, std::int64_t latency_ns, std::uint64_t missed) noexcept {
  period_->add(period_ns);
  latency_->add(latency_ns);
  if (missed > 0) {
    overruns_.fetch_add(1, std::memory_order_relaxed);
    missed_.fetch_add(missed, std::memory_order_relaxed);
  }
}

void TimingStats::reset() noexcept {
  for (Histogram* h : {period_.get(), latency_.get()}) {
    for (auto& b : h->bins) b.store(0, std::memory_order_relaxed);
    h->count.store(0);
    h->max_ns.store(0);
    h->sum_ns.store(0);
  }
  overruns_.store(0);
  missed_.store(0);
}

TimingReport TimingStats::report() const {
  TimingReport r;
  r.nominal_period_us = nominal_period_us_;
  r.samples = period_->count.load(std::memory_order_relaxed);
  r.period = period_->percentiles();
  r.wake_latency = latency_->percentiles();
  r.overruns = overruns_.load(std::memory_order_relaxed);
  r.missed_periods = missed_.load(std::memory_order_relaxed);
  return r;
}

void TimingStats::histograms(std::uint32_t* period, std::uint32_t* latency) const noexcept {
  for (int b = 0; b < kBins; ++b) {
    period[b] = period_->bins[b].load(std::memory_order_relaxed);
    latency[b] = latency_->bins[b].load(std::memory_order_relaxed);
  }
}

std::string TimingReport::format() const {
  char text[512];
  std::snprintf(text, sizeof text,
                "cycles %llu at nominal period %.1f us\n"
                "  period       mean %.1f  p50 %.0f  p90 %.0f  p99 %.0f  p99.9 %.0f  max %.1f us\n"
                "  wake latency mean %.1f  p50 %.0f  p90 %.0f  p99 %.0f  p99.9 %.0f  max %.1f us\n"
                "  overruns %llu (missed periods %llu)",
                static_cast<unsigned long long>(samples), nominal_period_us, period.mean_us, period.p50_us,
                period.p90_us, period.p99_us, period.p999_us, period.max_us, wake_latency.mean_us,
                wake_latency.p50_us, wake_latency.p90_us, wake_latency.p99_us, wake_latency.p999_us,
                wake_latency.max_us, static_cast<unsigned long long>(overruns),
                static_cast<unsigned long long>(missed_periods));
  return text;
}

}  // namespace uhaptics
