#pragma once
// The uhaptics board protocol (spec: devices/protocol/PROTOCOL.md): frame encoder and decoder.
//
// Pure functions over caller-owned byte buffers: no I/O, no heap, no exceptions, no Eigen, so the
// same code runs in the servo thread, in the board emulator, under libFuzzer and (it is plain C++17
// with fixed-width integers) in a board's firmware.
//
// Frame (all multi-byte fields little endian):
//   offset 0  u8  sync0 = 0xA5
//          1  u8  sync1 = 0x5A
//          2  u8  protocol version
//          3  u8  message type
//          4  u8  device type
//          5  u8  payload length L (0..kMaxPayload)
//          6  u16 sequence number
//          8  L bytes payload
//        8+L  u16 CRC-16/CCITT-FALSE over bytes [2, 8+L)
#include <array>
#include <cstddef>
#include <cstdint>

namespace uhaptics::wire {

inline constexpr std::uint8_t kSync0 = 0xA5;
inline constexpr std::uint8_t kSync1 = 0x5A;
/// Versions this implementation speaks. HELLO and DEVICE_INFO keep their layout in every version,
/// so two ends can always negotiate.
inline constexpr std::uint8_t kProtocolVersion = 1;
inline constexpr std::uint8_t kMinProtocolVersion = 1;
inline constexpr std::uint8_t kMaxProtocolVersion = 1;

inline constexpr std::size_t kHeaderSize = 8;
inline constexpr std::size_t kCrcSize = 2;
/// Largest joint or actuator count one frame carries (TAU: 6; headroom for 8-channel boards).
inline constexpr int kMaxChannels = 8;
inline constexpr std::size_t kStateFixedSize = 12;
inline constexpr std::size_t kStateReadingSize = 8;
inline constexpr std::size_t kCommandFixedSize = 4;
inline constexpr std::size_t kMaxPayload = kStateFixedSize + kStateReadingSize * kMaxChannels;
inline constexpr std::size_t kMaxFrameSize = kHeaderSize + kMaxPayload + kCrcSize;

enum class MessageType : std::uint8_t {
  kHello = 0x01,        // host -> board: open a session, offer a version range
  kDeviceInfo = 0x02,   // board -> host: answer to HELLO (version chosen, counts, rates)
  kConfigure = 0x03,    // host -> board: board watchdog timeout
  kAck = 0x04,          // board -> host: CONFIGURE accepted or refused
  kCommand = 0x10,      // host -> board: actuator commands (the board answers with STATE)
  kState = 0x11,        // board -> host: joint readings with timestamps, status
};

/// The device code in every frame's header. 0 is the emulator-only test plant; 1 .. kMaxDeviceCode
/// are the devices' codes, each assigned in the device's definition (devices/<device>/, see
/// uhaptics/backends/device_definition.hpp); higher codes are reserved and rejected.
enum class DeviceType : std::uint8_t {
  kTestPlant = 0x00,
};
inline constexpr std::uint8_t kMaxDeviceCode = 0x3F;

/// Board-side condition carried in STATE and ACK frames.
enum class BoardError : std::uint8_t {
  kNone = 0,
  kWatchdogExpired = 1,   // no valid COMMAND within the configured timeout: outputs forced to zero
  kSensorFault = 2,       // a joint sensor reading is invalid
  kActuatorFault = 3,     // amplifier/actuator reported a fault (over-current, over-temperature)
  kCommandClamped = 4,    // the board clamped a command to its own limits
  kNotConfigured = 5,     // COMMAND received before CONFIGURE: ignored, outputs stay zero
  kVersionMismatch = 6,   // HELLO offered no version the board speaks
  kBadFrame = 7,          // the board rejected a frame from the host (CRC, length, ...)
  kInvalidConfig = 8,     // CONFIGURE value outside what the board supports
};
inline constexpr std::uint8_t kMaxBoardError = 8;

/// STATE status flags.
namespace status {
inline constexpr std::uint8_t kConfigured = 1u << 0;      // CONFIGURE accepted since the last reset
inline constexpr std::uint8_t kOutputsEnabled = 1u << 1;  // actuators follow COMMAND
inline constexpr std::uint8_t kWatchdogTripped = 1u << 2; // board watchdog fired since last COMMAND
inline constexpr std::uint8_t kJustReset = 1u << 3;       // board (re)booted and no HELLO since
inline constexpr std::uint8_t kAllFlags = 0x0F;
}  // namespace status

/// Command modes.
enum class CommandMode : std::uint8_t {
  kEffort = 0,   // values are actuator efforts (N m for revolute, N for linear actuators)
  kZero = 1,     // outputs zero; values must be zero too
};

struct Hello {
  std::uint8_t min_version = kMinProtocolVersion;
  std::uint8_t max_version = kMaxProtocolVersion;
  std::uint32_t nonce = 0;   // echoed in DEVICE_INFO so a stale answer is recognised
};

struct DeviceInfo {
  std::uint8_t min_version = 0;       // range the board speaks
  std::uint8_t max_version = 0;
  std::uint8_t selected_version = 0;  // 0: no common version (session refused)
  std::uint8_t joint_count = 0;
  std::uint8_t actuator_count = 0;
  std::uint16_t sample_rate_hz = 0;   // board sensor sampling rate
  std::uint32_t firmware_version = 0;
  std::uint32_t nonce = 0;
};

struct Configure {
  std::uint32_t watchdog_timeout_us = 0;   // board zeroes its outputs after this long without COMMAND
};

struct Ack {
  std::uint16_t acked_sequence = 0;
  MessageType acked_type = MessageType::kConfigure;
  BoardError error = BoardError::kNone;
};

struct Command {
  CommandMode mode = CommandMode::kZero;
  std::uint8_t count = 0;
  std::array<float, kMaxChannels> values{};
};

struct State {
  std::uint32_t board_time_us = 0;           // board clock when the STATE was assembled
  std::uint16_t last_command_sequence = 0;   // sequence of the last COMMAND the board applied
  std::uint8_t status = 0;                   // status:: flags
  BoardError error = BoardError::kNone;
  std::uint8_t count = 0;                    // joint readings that follow
  std::array<float, kMaxChannels> position{};          // rad or m
  std::array<std::uint32_t, kMaxChannels> sample_time_us{};  // board clock at each sample
};

/// A decoded frame: header fields plus the one payload its type selects.
struct Frame {
  std::uint8_t version = kProtocolVersion;
  MessageType type = MessageType::kState;
  DeviceType device = DeviceType::kTestPlant;
  std::uint16_t sequence = 0;
  Hello hello;
  DeviceInfo info;
  Configure configure;
  Ack ack;
  Command command;
  State state;
};

/// Every reason the decoder refuses a frame. Each has its own counter in DecoderStats.
enum class Reject : std::uint8_t {
  kNone = 0,
  kTruncated,            // fewer bytes than the header or the declared payload needs
  kBadSync,              // first two bytes are not A5 5A
  kUnsupportedVersion,   // version outside [kMinProtocolVersion, kMaxProtocolVersion] (non-HELLO)
  kUnknownType,
  kUnknownDevice,       // device code above kMaxDeviceCode (reserved)
  kPayloadTooLong,       // declared length above kMaxPayload
  kBadLength,            // declared length does not match what the type (and its count) needs
  kBadCrc,
  kBadCount,             // joint/actuator count above kMaxChannels
  kNonFiniteValue,       // NaN or Inf in a float field
  kBadField,             // reserved byte not zero, unknown enum/flag value, zero-mode with values
  kTrailingBytes,        // buffer holds more than one frame's bytes
  kCount_,
};
inline constexpr std::size_t kRejectReasons = static_cast<std::size_t>(Reject::kCount_);

const char* toString(Reject r) noexcept;
const char* toString(BoardError e) noexcept;
/// A code in 0 .. kMaxDeviceCode (the decoder rejects the others as kUnknownDevice).
bool isKnownDevice(std::uint8_t raw) noexcept;

/// Accepted/rejected counters. Plain integers: owned by one thread (the one decoding).
struct DecoderStats {
  std::uint64_t accepted = 0;
  std::array<std::uint64_t, kRejectReasons> rejected{};
  std::uint64_t totalRejected() const noexcept;
  std::uint64_t count(Reject r) const noexcept { return rejected[static_cast<std::size_t>(r)]; }
};

/// CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF, no reflection, no xor-out); check("123456789") = 0x29B1.
std::uint16_t crc16Ccitt(const std::uint8_t* data, std::size_t size,
                         std::uint16_t crc = 0xFFFF) noexcept;

/// Writes one frame into out (capacity bytes). Returns the frame size, or 0 if out is too small or
/// the frame's content is invalid (count above kMaxChannels, non-finite value): the encoder never
/// produces a frame the decoder would reject.
std::size_t encode(const Frame& frame, std::uint8_t* out, std::size_t capacity) noexcept;

/// Decodes exactly one frame occupying all of [data, data+size). Never reads outside that range.
/// On failure out is unspecified and the reason is returned; stats (optional) counts the outcome.
Reject decode(const std::uint8_t* data, std::size_t size, Frame& out,
              DecoderStats* stats = nullptr) noexcept;

// Convenience constructors for the encoder side.
Frame makeHello(DeviceType device, std::uint16_t sequence, std::uint32_t nonce) noexcept;
Frame makeCommand(DeviceType device, std::uint16_t sequence, CommandMode mode, const double* values,
                  int count) noexcept;

/// True when sequence a was sent after b, with 16-bit wrap-around (serial number arithmetic).
constexpr bool sequenceAfter(std::uint16_t a, std::uint16_t b) noexcept {
  return a != b && static_cast<std::uint16_t>(a - b) < 0x8000u;
}

}  // namespace uhaptics::wire
