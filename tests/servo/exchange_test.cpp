// The wait-free exchange between the servo and graphics threads (run under ThreadSanitizer by
// tools/run-tests): a reader never sees a torn value, values arrive in order, nothing blocks.
#include <catch2/catch.hpp>

#include <thread>

#include "uhaptics/backends/lockfree.hpp"

namespace {
// Every field carries the same serial: a torn read (parts of two writes) shows as a mismatch.
struct Sample {
  std::uint64_t serial = 0;
  std::array<std::uint64_t, 15> copies{};
};
}  // namespace

TEST_CASE("triple buffer: the reader sees whole values, newest first, in order", "[servo][exchange]") {
  uhaptics::TripleBuffer<Sample> buffer;
  constexpr std::uint64_t kWrites = 200000;
  std::thread writer([&] {
    for (std::uint64_t i = 1; i <= kWrites; ++i) {
      Sample s;
      s.serial = i;
      s.copies.fill(i);
      buffer.write(s);
    }
  });
  std::uint64_t last = 0, reads = 0, torn = 0, backwards = 0;
  while (last < kWrites) {
    Sample s;
    if (!buffer.read(s)) continue;
    ++reads;
    for (const auto c : s.copies) torn += c != s.serial;
    backwards += s.serial <= last;
    last = s.serial;
  }
  writer.join();
  CHECK(torn == 0);
  CHECK(backwards == 0);
  CHECK(reads > 0);
  Sample s;
  CHECK_FALSE(buffer.read(s));  // nothing new after the last value was taken
  CHECK(s.serial == kWrites);
}

TEST_CASE("SPSC ring: FIFO order, no loss while there is room, refuses when full", "[servo][exchange]") {
  uhaptics::SpscRing<std::uint64_t, 64> ring;
  constexpr std::uint64_t kItems = 200000;
  std::uint64_t refused = 0;
  std::thread producer([&] {
    for (std::uint64_t i = 1; i <= kItems;) {
      if (ring.push(i)) ++i;
      else ++refused;  // full: the servo thread would count a dropped event and move on
    }
  });
  std::uint64_t expected = 1, out_of_order = 0, v = 0;
  while (expected <= kItems)
    if (ring.pop(v)) out_of_order += v != expected++;
  producer.join();
  CHECK(out_of_order == 0);
  CHECK_FALSE(ring.pop(v));

  uhaptics::SpscRing<int, 4> small;
  CHECK(small.push(1));
  CHECK(small.push(2));
  CHECK(small.push(3));
  CHECK_FALSE(small.push(4));  // capacity N-1
}
