// libFuzzer target for the wire-protocol decoder (built with clang -fsanitize=fuzzer,address,undefined
// by tests/fuzz/CMakeLists.txt). Properties checked on every input, beyond "no memory error":
//  - exactly one outcome is counted (accepted or one rejection reason);
//  - an accepted frame re-encodes to exactly the input bytes (the decoder accepts only canonical
//    frames and loses nothing), so encoder and decoder agree on the whole accepted language.
// Each input is decoded twice: as is, and with its last two bytes replaced by the correct CRC, so
// the fuzzer also explores the field checks behind the CRC instead of stopping at it.
#include <cstdint>
#include <cstdlib>
#include <cstring>

#include "uhaptics/protocol/wire_protocol.hpp"

namespace {
void check(const std::uint8_t* data, std::size_t size) {
  using namespace uhaptics::wire;
  Frame frame;
  DecoderStats stats;
  const Reject r = decode(data, size, frame, &stats);
  if (stats.accepted + stats.totalRejected() != 1) std::abort();
  if ((r == Reject::kNone) != (stats.accepted == 1)) std::abort();
  if (r == Reject::kNone) {
    std::uint8_t again[kMaxFrameSize];
    const std::size_t n = encode(frame, again, sizeof again);
    if (n != size || std::memcmp(again, data, size) != 0) std::abort();
  }
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace uhaptics::wire;
  check(data, size);
  std::uint8_t fixed[512];
  if (size >= kHeaderSize + kCrcSize && size <= sizeof fixed) {
    std::memcpy(fixed, data, size);
    const std::uint16_t crc = crc16Ccitt(fixed + 2, size - 2 - kCrcSize);
    fixed[size - 2] = static_cast<std::uint8_t>(crc & 0xFF);
    fixed[size - 1] = static_cast<std::uint8_t>(crc >> 8);
    check(fixed, size);
  }
  return 0;
}
