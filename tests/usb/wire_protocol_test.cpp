// Wire protocol: CRC check value, round trips, and one malformed-frame case per rejection reason.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstring>
#include <limits>
#include <algorithm>
#include <array>
#include <vector>

#include "uhaptics/protocol/wire_protocol.hpp"
#include "uhaptics/tools/alloc_probe.hpp"

using namespace uhaptics::wire;

namespace {

// A frame's bytes in fixed storage (tests edit them in place; room for over-long frames).
struct Bytes {
  std::array<std::uint8_t, 512> v{};
  std::size_t n = 0;
  explicit Bytes(std::size_t size = 0, std::uint8_t fill = 0) : n(size) { v.fill(fill); }
  std::uint8_t& operator[](std::size_t i) { return v[i]; }
  const std::uint8_t* data() const { return v.data(); }
  std::size_t size() const { return n; }
  void push_back(std::uint8_t b) { v[n++] = b; }
  bool operator==(const Bytes& o) const { return n == o.n && std::equal(v.begin(), v.begin() + n, o.v.begin()); }
};

Bytes bytesOf(const Frame& f) {
  Bytes out;
  out.n = encode(f, out.v.data(), kMaxFrameSize);
  REQUIRE(out.n > 0);
  return out;
}

// Recomputes the CRC after a test edits a field: exercises the field checks behind the CRC.
void fixCrc(Bytes& b) {
  const std::uint16_t crc = crc16Ccitt(b.data() + 2, b.size() - 4);
  b[b.size() - 2] = static_cast<std::uint8_t>(crc & 0xFF);
  b[b.size() - 1] = static_cast<std::uint8_t>(crc >> 8);
}

Frame sampleState(int joints) {
  Frame f;
  f.type = MessageType::kState;
  f.device = DeviceType{2};
  f.sequence = 0xFFFE;
  f.state.board_time_us = 123456789;
  f.state.last_command_sequence = 77;
  f.state.status = status::kConfigured | status::kOutputsEnabled;
  f.state.error = BoardError::kCommandClamped;
  f.state.count = static_cast<std::uint8_t>(joints);
  for (int i = 0; i < joints; ++i) {
    f.state.position[i] = 0.25f * static_cast<float>(i) - 1.0f;
    f.state.sample_time_us[i] = 1000u * static_cast<std::uint32_t>(i) + 5u;
  }
  return f;
}

Reject decodeBytes(const Bytes& b, DecoderStats* stats = nullptr) {
  Frame out;
  return decode(b.data(), b.size(), out, stats);
}

}  // namespace

TEST_CASE("CRC-16/CCITT-FALSE matches its published check value", "[usb][protocol]") {
  const char* check = "123456789";
  CHECK(crc16Ccitt(reinterpret_cast<const std::uint8_t*>(check), 9) == 0x29B1);
  CHECK(crc16Ccitt(nullptr, 0) == 0xFFFF);
}

TEST_CASE("every message type round-trips bit-exactly", "[usb][protocol]") {
  std::vector<Frame> frames;
  frames.push_back(makeHello(DeviceType{1}, 1, 0xDEADBEEF));
  Frame info;
  info.type = MessageType::kDeviceInfo;
  info.device = DeviceType{3};
  info.info = DeviceInfo{1, 3, 1, 4, 4, 1000, 0x00020001, 42};
  frames.push_back(info);
  Frame cfg;
  cfg.type = MessageType::kConfigure;
  cfg.configure.watchdog_timeout_us = 5000;
  frames.push_back(cfg);
  Frame ack;
  ack.type = MessageType::kAck;
  ack.ack = Ack{9, MessageType::kConfigure, BoardError::kInvalidConfig};
  frames.push_back(ack);
  const double efforts[6] = {0.5, -2.0, 1e-3, 0.0, -0.0, 1.75};
  frames.push_back(makeCommand(DeviceType{2}, 65535, CommandMode::kEffort, efforts, 6));
  frames.push_back(makeCommand(DeviceType{2}, 3, CommandMode::kZero, efforts, 6));
  for (int joints = 0; joints <= kMaxChannels; ++joints) frames.push_back(sampleState(joints));

  for (const Frame& f : frames) {
    const auto b = bytesOf(f);
    Frame out;
    DecoderStats stats;
    REQUIRE(decode(b.data(), b.size(), out, &stats) == Reject::kNone);
    CHECK(stats.accepted == 1);
    // Re-encoding what was decoded gives the same bytes: the decoder lost nothing.
    CHECK(bytesOf(out) == b);
    CHECK(out.type == f.type);
    CHECK(out.sequence == f.sequence);
  }
  Frame out;
  const auto cmd = bytesOf(frames[4]);
  REQUIRE(decode(cmd.data(), cmd.size(), out) == Reject::kNone);
  CHECK(out.command.count == 6);
  CHECK(out.command.values[1] == -2.0f);
  CHECK(std::signbit(out.command.values[4]));
  const auto st = bytesOf(sampleState(6));
  REQUIRE(decode(st.data(), st.size(), out) == Reject::kNone);
  CHECK(out.state.board_time_us == 123456789u);
  CHECK(out.state.position[5] == 0.25f);
  CHECK(out.state.sample_time_us[5] == 5005u);
  CHECK(out.state.error == BoardError::kCommandClamped);
}

TEST_CASE("every single-bit error and every truncation is rejected", "[usb][protocol]") {
  // CRC-16/CCITT detects all 1-bit errors; errors in sync/length bytes are caught before the CRC.
  const auto good = bytesOf(sampleState(6));
  DecoderStats stats;
  for (std::size_t byte = 0; byte < good.size(); ++byte)
    for (int bit = 0; bit < 8; ++bit) {
      auto b = good;
      b[byte] ^= static_cast<std::uint8_t>(1u << bit);
      CHECK(decodeBytes(b, &stats) != Reject::kNone);
    }
  CHECK(stats.accepted == 0);
  CHECK(stats.totalRejected() == good.size() * 8);
  CHECK(stats.count(Reject::kBadSync) == 16);
  CHECK(stats.count(Reject::kBadCrc) > 0);

  for (std::size_t n = 0; n < good.size(); ++n) {
    Frame out;
    CHECK(decode(good.data(), n, out) == Reject::kTruncated);
  }
  auto longer = good;
  longer.push_back(0);
  CHECK(decodeBytes(longer) == Reject::kTrailingBytes);
  Frame out;
  CHECK(decode(nullptr, 12, out) == Reject::kTruncated);
}

TEST_CASE("each malformed field is rejected with its own reason and counted", "[usb][protocol]") {
  DecoderStats stats;
  const auto state = bytesOf(sampleState(3));
  const auto expect = [&](Bytes b, Reject reason) {
    fixCrc(b);
    CHECK(std::string(toString(decodeBytes(b, &stats))) == toString(reason));
  };
  {
    auto b = state; b[2] = 2;  // a STATE in a version this build does not speak
    expect(b, Reject::kUnsupportedVersion);
    b[2] = 0;
    expect(b, Reject::kUnsupportedVersion);
  }
  { auto b = state; b[3] = 0x55; expect(b, Reject::kUnknownType); }
  { auto b = state; b[4] = 0x40; expect(b, Reject::kUnknownDevice); }
  {
    // Declared length above the maximum: rejected before the CRC is even looked at.
    Bytes b(kHeaderSize + 200 + kCrcSize);
    b[0] = kSync0; b[1] = kSync1; b[2] = 1; b[3] = 0x11; b[5] = 200;
    CHECK(decodeBytes(b, &stats) == Reject::kPayloadTooLong);
  }
  {
    // STATE claims 4 readings but carries 3: length and count disagree.
    auto b = state; b[kHeaderSize + 8] = 4; expect(b, Reject::kBadLength);
  }
  {
    // A count above the maximum.
    auto b = state; b[kHeaderSize + 8] = kMaxChannels + 1; expect(b, Reject::kBadCount);
  }
  {
    auto b = state;
    const float nan = std::numeric_limits<float>::quiet_NaN();
    std::memcpy(&b[kHeaderSize + 12], &nan, 4);
    expect(b, Reject::kNonFiniteValue);
    const float inf = std::numeric_limits<float>::infinity();
    std::memcpy(&b[kHeaderSize + 12], &inf, 4);
    expect(b, Reject::kNonFiniteValue);
  }
  { auto b = state; b[kHeaderSize + 9] = 1; expect(b, Reject::kBadField); }       // reserved byte
  { auto b = state; b[kHeaderSize + 6] = 0x80; expect(b, Reject::kBadField); }    // unknown status flag
  { auto b = state; b[kHeaderSize + 7] = 99; expect(b, Reject::kBadField); }      // unknown error code
  {
    const double one = 1.0;
    auto b = bytesOf(makeCommand(DeviceType{1}, 1, CommandMode::kZero, &one, 1));
    const float f = 1.0f;  // zero mode with a non-zero value
    std::memcpy(&b[kHeaderSize + 4], &f, 4);
    expect(b, Reject::kBadField);
    b[kHeaderSize] = 7;  // unknown mode
    expect(b, Reject::kBadField);
  }
  {
    Frame cfg;
    cfg.type = MessageType::kConfigure;
    cfg.configure.watchdog_timeout_us = 1;
    auto b = bytesOf(cfg);
    std::memset(&b[kHeaderSize], 0, 4);  // a zero watchdog would mean "none": refused
    expect(b, Reject::kBadField);
  }
  CHECK(stats.accepted == 0);
  CHECK(stats.totalRejected() == 15);
  CHECK(stats.count(Reject::kBadField) == 6);
  CHECK(stats.count(Reject::kNonFiniteValue) == 2);
}

TEST_CASE("HELLO keeps its layout across versions so negotiation always works", "[usb][protocol]") {
  Frame hello = makeHello(DeviceType{2}, 0, 1);
  hello.version = 9;  // a future host
  hello.hello.min_version = 2;
  hello.hello.max_version = 9;
  const auto b = bytesOf(hello);
  Frame out;
  REQUIRE(decode(b.data(), b.size(), out) == Reject::kNone);
  CHECK(out.version == 9);
  CHECK(out.hello.max_version == 9);
  Frame bad = hello;
  bad.hello.min_version = 5;
  bad.hello.max_version = 4;
  std::uint8_t buf[kMaxFrameSize];
  CHECK(encode(bad, buf, sizeof buf) == 0);  // an inverted range is never emitted
}

TEST_CASE("the encoder refuses frames the decoder would reject and never overruns", "[usb][protocol]") {
  std::uint8_t buf[kMaxFrameSize];
  const double nan = std::nan("");
  CHECK(encode(makeCommand(DeviceType{2}, 0, CommandMode::kEffort, &nan, 1), buf, sizeof buf) == 0);
  const double huge = 1e300;  // beyond float range
  CHECK(encode(makeCommand(DeviceType{2}, 0, CommandMode::kEffort, &huge, 1), buf, sizeof buf) == 0);
  Frame f = sampleState(kMaxChannels);
  f.state.count = kMaxChannels + 1;
  CHECK(encode(f, buf, sizeof buf) == 0);
  f.state.count = kMaxChannels;
  const std::size_t full = encode(f, buf, sizeof buf);
  CHECK(full == kMaxFrameSize);
  for (std::size_t cap = 0; cap < full; ++cap) CHECK(encode(f, buf, cap) == 0);
}

TEST_CASE("sequence comparison wraps around", "[usb][protocol]") {
  CHECK(sequenceAfter(1, 0));
  CHECK(sequenceAfter(0, 0xFFFF));
  CHECK_FALSE(sequenceAfter(0xFFFF, 0));
  CHECK_FALSE(sequenceAfter(5, 5));
}

TEST_CASE("encoding and decoding allocate nothing", "[usb][protocol]") {
  std::uint8_t buf[kMaxFrameSize];
  Frame f = sampleState(6), out;
  DecoderStats stats;
  uhaptics::tools::AllocationScope scope;
  for (int i = 0; i < 1000; ++i) {
    f.sequence = static_cast<std::uint16_t>(i);
    const std::size_t n = encode(f, buf, sizeof buf);
    buf[n / 2] = static_cast<std::uint8_t>(buf[n / 2] ^ (i & 1));  // every other frame corrupted
    decode(buf, n, out, &stats);
  }
  CHECK(scope.count() == 0);
  CHECK(stats.accepted == 500);
  CHECK(stats.count(Reject::kBadCrc) == 500);
}
