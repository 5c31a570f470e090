#include "uhaptics/protocol/wire_protocol.hpp"

#include <cmath>
#include <cstring>
#include <limits>

namespace uhaptics::wire {
namespace {

// Little-endian field access through an explicit cursor that knows its end, so no read or write can
// leave the buffer even if a length computation were wrong (each access is checked).
class Writer {
 public:
  Writer(std::uint8_t* data, std::size_t capacity) noexcept : data_(data), capacity_(capacity) {}
  void u8(std::uint8_t v) noexcept {
    if (pos_ + 1 > capacity_) { ok_ = false; return; }
    data_[pos_++] = v;
  }
  void u16(std::uint16_t v) noexcept {
    u8(static_cast<std::uint8_t>(v & 0xFFu));
    u8(static_cast<std::uint8_t>(v >> 8));
  }
  void u32(std::uint32_t v) noexcept {
    for (int shift = 0; shift < 32; shift += 8) u8(static_cast<std::uint8_t>((v >> shift) & 0xFFu));
  }
  void f32(float v) noexcept {
    std::uint32_t bits = 0;
    std::memcpy(&bits, &v, sizeof bits);
    u32(bits);
  }
  std::size_t size() const noexcept { return pos_; }
  bool ok() const noexcept { return ok_; }
  std::uint8_t* at(std::size_t i) noexcept { return data_ + i; }

 private:
  std::uint8_t* data_;
  std::size_t capacity_;
  std::size_t pos_ = 0;
  bool ok_ = true;
};

class Reader {
 public:
  Reader(const std::uint8_t* data, std::size_t size) noexcept : data_(data), size_(size) {}
  std::uint8_t u8() noexcept {
    if (pos_ + 1 > size_) { ok_ = false; return 0; }
    return data_[pos_++];
  }
  std::uint16_t u16() noexcept {
    const std::uint16_t lo = u8();
    const std::uint16_t hi = u8();
    return static_cast<std::uint16_t>(lo | (hi << 8));
  }
  std::uint32_t u32() noexcept {
    std::uint32_t v = 0;
    for (int shift = 0; shift < 32; shift += 8) v |= static_cast<std::uint32_t>(u8()) << shift;
    return v;
  }
  float f32() noexcept {
    const std::uint32_t bits = u32();
    float v = 0.0f;
    std::memcpy(&v, &bits, sizeof v);
    return v;
  }
  bool ok() const noexcept { return ok_; }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t pos_ = 0;
  bool ok_ = true;
};

constexpr std::array<std::uint16_t, 256> makeCrcTable() noexcept {
  std::array<std::uint16_t, 256> table{};
  for (unsigned i = 0; i < 256; ++i) {
    unsigned crc = i << 8;
    for (int bit = 0; bit < 8; ++bit) crc = (crc & 0x8000u) ? ((crc << 1) ^ 0x1021u) : (crc << 1);
    table[i] = static_cast<std::uint16_t>(crc & 0xFFFFu);
  }
  return table;
}
constexpr auto kCrcTable = makeCrcTable();

bool isKnownType(std::uint8_t raw) noexcept {
  switch (static_cast<MessageType>(raw)) {
    case MessageType::kHello:
    case MessageType::kDeviceInfo:
    case MessageType::kConfigure:
    case MessageType::kAck:
    case MessageType::kCommand:
    case MessageType::kState: return true;
  }
  return false;
}

// HELLO and DEVICE_INFO keep their layout in every protocol version so that negotiation works
// between any two versions; every other type must carry a version this side speaks.
bool versionFrozen(MessageType t) noexcept {
  return t == MessageType::kHello || t == MessageType::kDeviceInfo;
}

// Payload size a type needs, given the count byte for variable-length types.
std::size_t payloadSize(MessageType t, std::size_t count) noexcept {
  switch (t) {
    case MessageType::kHello: return 8;
    case MessageType::kDeviceInfo: return 16;
    case MessageType::kConfigure: return 4;
    case MessageType::kAck: return 4;
    case MessageType::kCommand: return kCommandFixedSize + 4 * count;
    case MessageType::kState: return kStateFixedSize + kStateReadingSize * count;
  }
  return 0;
}

std::size_t countOf(const Frame& f) noexcept {
  if (f.type == MessageType::kCommand) return f.command.count;
  if (f.type == MessageType::kState) return f.state.count;
  return 0;
}

Reject count(DecoderStats* stats, Reject r) noexcept {
  if (stats != nullptr) {
    if (r == Reject::kNone) ++stats->accepted;
    else ++stats->rejected[static_cast<std::size_t>(r)];
  }
  return r;
}

Reject decodePayload(Reader& in, Frame& out) noexcept {
  switch (out.type) {
    case MessageType::kHello: {
      out.hello.min_version = in.u8();
      out.hello.max_version = in.u8();
      const std::uint16_t reserved = in.u16();
      out.hello.nonce = in.u32();
      if (reserved != 0 || out.hello.min_version == 0 || out.hello.min_version > out.hello.max_version)
        return Reject::kBadField;
      return Reject::kNone;
    }
    case MessageType::kDeviceInfo: {
      DeviceInfo& d = out.info;
      d.min_version = in.u8();
      d.max_version = in.u8();
      d.selected_version = in.u8();
      d.joint_count = in.u8();
      d.actuator_count = in.u8();
      const std::uint8_t reserved = in.u8();
      d.sample_rate_hz = in.u16();
      d.firmware_version = in.u32();
      d.nonce = in.u32();
      if (reserved != 0 || d.min_version == 0 || d.min_version > d.max_version) return Reject::kBadField;
      if (d.selected_version != 0 &&
          (d.selected_version < d.min_version || d.selected_version > d.max_version))
        return Reject::kBadField;
      if (d.joint_count > kMaxChannels || d.actuator_count > kMaxChannels) return Reject::kBadCount;
      return Reject::kNone;
    }
    case MessageType::kConfigure:
      out.configure.watchdog_timeout_us = in.u32();
      return out.configure.watchdog_timeout_us == 0 ? Reject::kBadField : Reject::kNone;
    case MessageType::kAck: {
      out.ack.acked_sequence = in.u16();
      const std::uint8_t type = in.u8();
      const std::uint8_t error = in.u8();
      if (!isKnownType(type) || error > kMaxBoardError) return Reject::kBadField;
      out.ack.acked_type = static_cast<MessageType>(type);
      out.ack.error = static_cast<BoardError>(error);
      return Reject::kNone;
    }
    case MessageType::kCommand: {
      Command& c = out.command;
      const std::uint8_t mode = in.u8();
      c.count = in.u8();  // already range-checked by the caller
      const std::uint16_t reserved = in.u16();
      if (reserved != 0 || mode > static_cast<std::uint8_t>(CommandMode::kZero)) return Reject::kBadField;
      c.mode = static_cast<CommandMode>(mode);
      c.values.fill(0.0f);
      for (int i = 0; i < c.count; ++i) {
        c.values[i] = in.f32();
        if (!std::isfinite(c.values[i])) return Reject::kNonFiniteValue;
        if (c.mode == CommandMode::kZero && c.values[i] != 0.0f) return Reject::kBadField;
      }
      return Reject::kNone;
    }
    case MessageType::kState: {
      State& s = out.state;
      s.board_time_us = in.u32();
      s.last_command_sequence = in.u16();
      s.status = in.u8();
      const std::uint8_t error = in.u8();
      s.count = in.u8();
      const std::uint8_t r0 = in.u8(), r1 = in.u8(), r2 = in.u8();
      if ((s.status & ~status::kAllFlags) != 0 || error > kMaxBoardError || (r0 | r1 | r2) != 0)
        return Reject::kBadField;
      s.error = static_cast<BoardError>(error);
      s.position.fill(0.0f);
      s.sample_time_us.fill(0);
      for (int i = 0; i < s.count; ++i) {
        s.position[i] = in.f32();
        s.sample_time_us[i] = in.u32();
        if (!std::isfinite(s.position[i])) return Reject::kNonFiniteValue;
      }
      return Reject::kNone;
    }
  }
  return Reject::kUnknownType;
}

}  // namespace

const char* toString(Reject r) noexcept {
  switch (r) {
    case Reject::kNone: return "accepted";
    case Reject::kTruncated: return "truncated frame";
    case Reject::kBadSync: return "bad sync bytes";
    case Reject::kUnsupportedVersion: return "unsupported protocol version";
    case Reject::kUnknownType: return "unknown message type";
    case Reject::kUnknownDevice: return "reserved device code";
    case Reject::kPayloadTooLong: return "payload length above maximum";
    case Reject::kBadLength: return "payload length does not match message type";
    case Reject::kBadCrc: return "CRC mismatch";
    case Reject::kBadCount: return "channel count above maximum";
    case Reject::kNonFiniteValue: return "non-finite value";
    case Reject::kBadField: return "invalid field value";
    case Reject::kTrailingBytes: return "trailing bytes after frame";
    case Reject::kCount_: break;
  }
  return "unknown reason";
}

const char* toString(BoardError e) noexcept {
  switch (e) {
    case BoardError::kNone: return "none";
    case BoardError::kWatchdogExpired: return "board watchdog expired (outputs zeroed)";
    case BoardError::kSensorFault: return "sensor fault";
    case BoardError::kActuatorFault: return "actuator fault";
    case BoardError::kCommandClamped: return "command clamped by the board";
    case BoardError::kNotConfigured: return "board not configured";
    case BoardError::kVersionMismatch: return "protocol version mismatch";
    case BoardError::kBadFrame: return "board rejected a host frame";
    case BoardError::kInvalidConfig: return "invalid configuration";
  }
  return "unknown board error";
}

bool isKnownDevice(std::uint8_t raw) noexcept {
  return raw <= kMaxDeviceCode;
}

std::uint64_t DecoderStats::totalRejected() const noexcept {
  std::uint64_t total = 0;
  for (const auto n : rejected) total += n;
  return total;
}

std::uint16_t crc16Ccitt(const std::uint8_t* data, std::size_t size, std::uint16_t crc) noexcept {
  for (std::size_t i = 0; i < size; ++i)
    crc = static_cast<std::uint16_t>((crc << 8) ^ kCrcTable[((crc >> 8) ^ data[i]) & 0xFFu]);
  return crc;
}

std::size_t encode(const Frame& f, std::uint8_t* out, std::size_t capacity) noexcept {
  const std::size_t n = countOf(f);
  if (n > static_cast<std::size_t>(kMaxChannels) || !isKnownType(static_cast<std::uint8_t>(f.type)) ||
      !isKnownDevice(static_cast<std::uint8_t>(f.device)) || out == nullptr)
    return 0;
  const std::size_t payload = payloadSize(f.type, n);
  Writer w(out, capacity);
  w.u8(kSync0);
  w.u8(kSync1);
  w.u8(f.version);
  w.u8(static_cast<std::uint8_t>(f.type));
  w.u8(static_cast<std::uint8_t>(f.device));
  w.u8(static_cast<std::uint8_t>(payload));
  w.u16(f.sequence);
  switch (f.type) {
    case MessageType::kHello:
      w.u8(f.hello.min_version);
      w.u8(f.hello.max_version);
      w.u16(0);
      w.u32(f.hello.nonce);
      break;
    case MessageType::kDeviceInfo:
      w.u8(f.info.min_version);
      w.u8(f.info.max_version);
      w.u8(f.info.selected_version);
      w.u8(f.info.joint_count);
      w.u8(f.info.actuator_count);
      w.u8(0);
      w.u16(f.info.sample_rate_hz);
      w.u32(f.info.firmware_version);
      w.u32(f.info.nonce);
      break;
    case MessageType::kConfigure: w.u32(f.configure.watchdog_timeout_us); break;
    case MessageType::kAck:
      w.u16(f.ack.acked_sequence);
      w.u8(static_cast<std::uint8_t>(f.ack.acked_type));
      w.u8(static_cast<std::uint8_t>(f.ack.error));
      break;
    case MessageType::kCommand:
      w.u8(static_cast<std::uint8_t>(f.command.mode));
      w.u8(f.command.count);
      w.u16(0);
      for (std::size_t i = 0; i < n; ++i) {
        if (!std::isfinite(f.command.values[i])) return 0;
        w.f32(f.command.values[i]);
      }
      break;
    case MessageType::kState:
      w.u32(f.state.board_time_us);
      w.u16(f.state.last_command_sequence);
      w.u8(f.state.status);
      w.u8(static_cast<std::uint8_t>(f.state.error));
      w.u8(f.state.count);
      w.u8(0);
      w.u8(0);
      w.u8(0);
      for (std::size_t i = 0; i < n; ++i) {
        if (!std::isfinite(f.state.position[i])) return 0;
        w.f32(f.state.position[i]);
        w.u32(f.state.sample_time_us[i]);
      }
      break;
  }
  if (!w.ok()) return 0;
  const std::uint16_t crc = crc16Ccitt(w.at(2), w.size() - 2);
  w.u16(crc);
  if (!w.ok()) return 0;
  // Round-trip guarantee: refuse to emit anything the decoder would reject (bad enum values etc.).
  Frame check;
  if (decode(out, w.size(), check) != Reject::kNone) return 0;
  return w.size();
}

Reject decode(const std::uint8_t* data, std::size_t size, Frame& out, DecoderStats* stats) noexcept {
  if (data == nullptr || size < kHeaderSize + kCrcSize) return count(stats, Reject::kTruncated);
  if (data[0] != kSync0 || data[1] != kSync1) return count(stats, Reject::kBadSync);
  const std::uint8_t version = data[2];
  const std::uint8_t type = data[3];
  const std::uint8_t device = data[4];
  const std::size_t length = data[5];
  if (length > kMaxPayload) return count(stats, Reject::kPayloadTooLong);
  const std::size_t frame_size = kHeaderSize + length + kCrcSize;
  if (size < frame_size) return count(stats, Reject::kTruncated);
  if (size > frame_size) return count(stats, Reject::kTrailingBytes);
  // CRC before any field interpretation: a corrupted frame is reported as corrupted, not as
  // whatever its flipped bits happen to look like.
  const std::uint16_t crc_read =
      static_cast<std::uint16_t>(data[frame_size - 2] | (data[frame_size - 1] << 8));
  if (crc16Ccitt(data + 2, frame_size - 2 - kCrcSize) != crc_read) return count(stats, Reject::kBadCrc);
  if (!isKnownType(type)) return count(stats, Reject::kUnknownType);
  out.type = static_cast<MessageType>(type);
  if (version == 0 || (!versionFrozen(out.type) &&
                       (version < kMinProtocolVersion || version > kMaxProtocolVersion)))
    return count(stats, Reject::kUnsupportedVersion);
  if (!isKnownDevice(device)) return count(stats, Reject::kUnknownDevice);
  out.version = version;
  out.device = static_cast<DeviceType>(device);
  out.sequence = static_cast<std::uint16_t>(data[6] | (data[7] << 8));

  std::size_t channels = 0;
  if (out.type == MessageType::kCommand || out.type == MessageType::kState) {
    // The count byte sits at payload offset 1 (COMMAND) or 8 (STATE); it must be inside the payload.
    const std::size_t at = out.type == MessageType::kCommand ? 1 : 8;
    if (length <= at) return count(stats, Reject::kBadLength);
    channels = data[kHeaderSize + at];
    if (channels > static_cast<std::size_t>(kMaxChannels)) return count(stats, Reject::kBadCount);
  }
  if (length != payloadSize(out.type, channels)) return count(stats, Reject::kBadLength);

  Reader in(data + kHeaderSize, length);
  const Reject r = decodePayload(in, out);
  if (r != Reject::kNone) return count(stats, r);
  if (!in.ok()) return count(stats, Reject::kTruncated);  // unreachable when lengths agree; kept as a guard
  return count(stats, Reject::kNone);
}

Frame makeHello(DeviceType device, std::uint16_t sequence, std::uint32_t nonce) noexcept {
  Frame f;
  f.type = MessageType::kHello;
  f.device = device;
  f.sequence = sequence;
  f.hello.nonce = nonce;
  return f;
}

Frame makeCommand(DeviceType device, std::uint16_t sequence, CommandMode mode, const double* values,
                  int count) noexcept {
  Frame f;
  f.type = MessageType::kCommand;
  f.device = device;
  f.sequence = sequence;
  f.command.mode = mode;
  f.command.count = static_cast<std::uint8_t>(count < 0 ? 0 : (count > kMaxChannels ? kMaxChannels : count));
  for (int i = 0; i < f.command.count; ++i) {
    const double v = mode == CommandMode::kZero ? 0.0 : values[i];
    // A value beyond float range would be undefined behaviour to convert: make it NaN so that
    // encode() refuses the frame instead.
    f.command.values[i] = std::abs(v) <= static_cast<double>(std::numeric_limits<float>::max())
                              ? static_cast<float>(v)
                              : std::numeric_limits<float>::quiet_NaN();
  }
  return f;
}

}  // namespace uhaptics::wire
