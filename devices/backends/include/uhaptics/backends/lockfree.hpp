#pragma once
// Wait-free single-producer/single-consumer exchange between the servo thread and the graphics (or
// any other) thread. Neither side ever blocks or allocates, so the servo thread cannot be held up
// by a slow renderer, and the graphics thread always sees a complete, consistent snapshot.
#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <type_traits>

namespace uhaptics {

/// Latest-value exchange (triple buffering): the writer publishes whole values, the reader gets the
/// most recent complete one. Exactly one writer thread and one reader thread.
template <typename T>
class TripleBuffer {
  static_assert(std::is_trivially_copyable_v<T>, "snapshots are copied by value");

 public:
  /// Publishes a value (writer thread).
  void write(const T& value) noexcept {
    slots_[back_] = value;
    back_ = static_cast<std::uint8_t>(middle_.exchange(static_cast<std::uint8_t>(back_ | kFresh),
                                                       std::memory_order_acq_rel) & kIndex);
  }
  /// Copies the newest published value into out (reader thread). Returns false, and the previous
  /// value, when nothing new was published since the last read.
  bool read(T& out) noexcept {
    const bool fresh = (middle_.load(std::memory_order_relaxed) & kFresh) != 0;
    if (fresh) front_ = static_cast<std::uint8_t>(middle_.exchange(front_, std::memory_order_acq_rel) & kIndex);
    out = slots_[front_];
    return fresh;
  }

 private:
  static constexpr std::uint8_t kIndex = 0x3;
  static constexpr std::uint8_t kFresh = 0x4;
  std::array<T, 3> slots_{};
  std::atomic<std::uint8_t> middle_{1};
  std::uint8_t back_ = 0;   // writer-owned
  std::uint8_t front_ = 2;  // reader-owned
};

/// Bounded FIFO (ring buffer) of N-1 entries. push() fails instead of blocking when full; the
/// caller counts what it could not push.
template <typename T, std::size_t N>
class SpscRing {
  static_assert(std::is_trivially_copyable_v<T>);
  static_assert(N >= 2 && (N & (N - 1)) == 0, "capacity is a power of two");

 public:
  bool push(const T& value) noexcept {
    const std::size_t head = head_.load(std::memory_order_relaxed);
    const std::size_t next = (head + 1) & (N - 1);
    if (next == tail_.load(std::memory_order_acquire)) return false;
    items_[head] = value;
    head_.store(next, std::memory_order_release);
    return true;
  }
  bool pop(T& out) noexcept {
    const std::size_t tail = tail_.load(std::memory_order_relaxed);
    if (tail == head_.load(std::memory_order_acquire)) return false;
    out = items_[tail];
    tail_.store((tail + 1) & (N - 1), std::memory_order_release);
    return true;
  }

 private:
  std::array<T, N> items_{};
  alignas(64) std::atomic<std::size_t> head_{0};  // producer
  alignas(64) std::atomic<std::size_t> tail_{0};  // consumer
};

}  // namespace uhaptics
