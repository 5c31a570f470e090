#pragma once
// Transport over libusb-1.0 bulk endpoints to a uhaptics controller board.
//
// Opening (set-up time, throws uhaptics::Error with what to do about it):
//   libusb_init -> enumerate -> match vendor/product id from the device's parameter file -> open
//   (permission denied: install share/uhaptics/udev/99-uhaptics.rules) -> detach a kernel driver
//   if one is bound -> claim the interface (busy: another program holds it) -> arm the IN transfer.
// Servo path (never throws, never allocates): OUT frames are synchronous bulk transfers with a
// timeout; IN frames arrive through one permanently re-armed asynchronous transfer so receive() can
// wait with microsecond timeouts (libusb's synchronous calls only take milliseconds, 0 = forever).
// Hot-unplug: any LIBUSB_ERROR_NO_DEVICE turns into TransportStatus::kDisconnected; reconnect()
// closes what is left and repeats the opening steps, returning false until the board is back.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "uhaptics/protocol/device_descriptor.hpp"
#include "uhaptics/protocol/transport.hpp"

struct libusb_context;
struct libusb_device_handle;
struct libusb_transfer;

namespace uhaptics {

class LibusbTransport final : public Transport {
 public:
  /// Finds and opens the board described by `device`; throws Error (see above) when it cannot.
  explicit LibusbTransport(const DeviceDescriptor& device);
  ~LibusbTransport() override;

  TransportStatus send(const std::uint8_t* data, std::size_t size, int timeout_us) noexcept override;
  TransportStatus receive(std::uint8_t* buffer, std::size_t capacity, std::size_t& received,
                          int timeout_us) noexcept override;
  bool reconnect() noexcept override;
  const char* describe() const noexcept override { return description_.c_str(); }

  /// Every USB device libusb can see, one "bus B addr A vvvv:pppp" line each (for error messages).
  static std::vector<std::string> listDevices();

  // Implementation detail shared with the libusb completion callback.
  struct InQueue;

 private:
  void open();            // throws Error
  void close() noexcept;  // releases the interface, reattaches the kernel driver, closes
  bool armIn() noexcept;

  DeviceDescriptor device_;
  std::string description_;
  libusb_context* context_ = nullptr;
  libusb_device_handle* handle_ = nullptr;
  libusb_transfer* in_transfer_ = nullptr;
  InQueue* in_queue_ = nullptr;
  bool claimed_ = false;
};

/// The message for a libusb error code during opening: what happened and what to do.
std::string libusbOpenAdvice(int libusb_error, const DeviceDescriptor& device);

}  // namespace uhaptics
