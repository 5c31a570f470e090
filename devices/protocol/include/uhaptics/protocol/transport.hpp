#pragma once
// The byte pipe between the host and a device's controller board. One frame per transfer (the
// protocol's frames fit one USB bulk packet sequence; see devices/protocol/PROTOCOL.md).
// Implementations: LibusbTransport (hardware) and BoardEmulator (in-process board for tests).
//
// send/receive are called from the servo thread: they never throw and never allocate.
// reconnect() is the one exception: it may allocate (libusb enumerates) and is only called while
// the device is absent, at a low rate.
#include <cstddef>
#include <cstdint>

namespace uhaptics {

enum class TransportStatus : std::uint8_t {
  kOk = 0,
  kTimeout,        // nothing arrived (or could be sent) within the timeout
  kDisconnected,   // the device is gone (unplugged); reconnect() may bring it back
  kError,          // any other transfer error (counted; the servo loop treats it as a lost frame)
};

constexpr const char* toString(TransportStatus s) noexcept {
  switch (s) {
    case TransportStatus::kOk: return "ok";
    case TransportStatus::kTimeout: return "timeout";
    case TransportStatus::kDisconnected: return "disconnected";
    case TransportStatus::kError: return "transfer error";
  }
  return "unknown";
}

class Transport {
 public:
  virtual ~Transport() = default;
  Transport() = default;
  Transport(const Transport&) = delete;
  Transport& operator=(const Transport&) = delete;

  /// Sends one frame.
  virtual TransportStatus send(const std::uint8_t* data, std::size_t size, int timeout_us) noexcept = 0;
  /// Receives one frame into buffer (capacity bytes); received is the byte count on kOk.
  virtual TransportStatus receive(std::uint8_t* buffer, std::size_t capacity, std::size_t& received,
                                  int timeout_us) noexcept = 0;
  /// After kDisconnected: tries once to find and open the device again. True when it is back.
  virtual bool reconnect() noexcept = 0;
  /// Human-readable name of the endpoint (for reports), e.g. "usb 1209:0002 bus 1 addr 7".
  virtual const char* describe() const noexcept = 0;
};

}  // namespace uhaptics
