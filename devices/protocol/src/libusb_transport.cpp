#include "uhaptics/protocol/libusb_transport.hpp"

#include <libusb.h>

#include <algorithm>
#include <cstdio>
#include <cstring>

#include "uhaptics/core/fault.hpp"

namespace uhaptics {
namespace {

std::string usbId(std::uint16_t vid, std::uint16_t pid) {
  char text[16];
  std::snprintf(text, sizeof text, "%04x:%04x", vid, pid);
  return text;
}

// Generated from the parameter files into the build folder and installed with uhaptics (both under
// share/uhaptics/udev/).
constexpr const char* kUdevRules = "share/uhaptics/udev/99-uhaptics.rules";

TransportStatus fromLibusb(int err) noexcept {
  switch (err) {
    case LIBUSB_SUCCESS: return TransportStatus::kOk;
    case LIBUSB_ERROR_TIMEOUT: return TransportStatus::kTimeout;
    case LIBUSB_ERROR_NO_DEVICE:
    case LIBUSB_ERROR_NOT_FOUND: return TransportStatus::kDisconnected;
    default: return TransportStatus::kError;
  }
}

}  // namespace

// Completed IN frames, filled by the completion callback (which runs inside
// libusb_handle_events_*, i.e. in the thread calling receive()), drained by receive().
struct LibusbTransport::InQueue {
  static constexpr std::size_t kFrames = 8;
  std::array<std::array<std::uint8_t, wire::kMaxFrameSize>, kFrames> frames{};
  std::array<std::size_t, kFrames> sizes{};
  std::size_t head = 0, count = 0;
  std::array<std::uint8_t, 512> buffer{};  // one full-/high-speed bulk packet (frames are shorter)
  bool disconnected = false;
  bool error = false;
  bool completed = false;  // set by the callback: wakes libusb_handle_events_timeout_completed
};

namespace {
void LIBUSB_CALL onInComplete(libusb_transfer* transfer) {
  auto* q = static_cast<LibusbTransport::InQueue*>(transfer->user_data);
  q->completed = true;
  switch (transfer->status) {
    case LIBUSB_TRANSFER_COMPLETED:
      if (q->count < LibusbTransport::InQueue::kFrames && transfer->actual_length > 0) {
        // A transfer longer than any frame is cut to kMaxFrameSize bytes: the decoder rejects it.
        const std::size_t n = std::min<std::size_t>(static_cast<std::size_t>(transfer->actual_length), wire::kMaxFrameSize);
        const std::size_t slot = (q->head + q->count) % LibusbTransport::InQueue::kFrames;
        std::memcpy(q->frames[slot].data(), q->buffer.data(), n);
        q->sizes[slot] = n;
        ++q->count;
      }
      if (libusb_submit_transfer(transfer) != LIBUSB_SUCCESS) q->error = true;
      break;
    case LIBUSB_TRANSFER_NO_DEVICE: q->disconnected = true; break;
    case LIBUSB_TRANSFER_CANCELLED: break;
    default:  // stall, overflow, error: re-arm; the servo loop sees a missing STATE
      if (libusb_submit_transfer(transfer) != LIBUSB_SUCCESS) q->error = true;
      break;
  }
}
}  // namespace

std::string libusbOpenAdvice(int err, const DeviceDescriptor& d) {
  const std::string who = d.name + " (USB " + usbId(d.vendor_id, d.product_id) + ")";
  switch (err) {
    case LIBUSB_ERROR_ACCESS:
      return "permission denied opening " + who + ". Install uhaptics' udev rules and replug:\n"
             "  sudo cp <uhaptics>/" + std::string(kUdevRules) + " /etc/udev/rules.d/ && sudo udevadm control "
             "--reload-rules && sudo udevadm trigger\n  (<uhaptics>: its installation prefix or its build folder; "
             "the rules grant the 'plugdev' group access; add yourself with `sudo usermod -aG plugdev $USER` and "
             "log in again)";
    case LIBUSB_ERROR_BUSY:
      return "interface " + std::to_string(d.interface_number) + " of " + who +
             " is busy: another program (another uhaptics application?) has claimed it. Close it and retry";
    case LIBUSB_ERROR_NO_DEVICE:
      return who + " disappeared while being opened (unplugged or rebooting). Check the cable and retry";
    case LIBUSB_ERROR_NOT_FOUND:
      return "interface " + std::to_string(d.interface_number) + " does not exist on " + who +
             ": check usb/interface in the device's parameter file";
    default:
      return std::string("libusb error opening ") + who + ": " + libusb_strerror(static_cast<libusb_error>(err));
  }
}

std::vector<std::string> LibusbTransport::listDevices() {
  std::vector<std::string> found;
  libusb_context* ctx = nullptr;
  if (libusb_init(&ctx) != LIBUSB_SUCCESS) return found;
  libusb_device** list = nullptr;
  const ssize_t n = libusb_get_device_list(ctx, &list);
  for (ssize_t i = 0; i < n; ++i) {
    libusb_device_descriptor desc{};
    if (libusb_get_device_descriptor(list[i], &desc) != LIBUSB_SUCCESS) continue;
    char line[64];
    std::snprintf(line, sizeof line, "bus %u addr %u %04x:%04x", libusb_get_bus_number(list[i]),
                  libusb_get_device_address(list[i]), desc.idVendor, desc.idProduct);
    found.emplace_back(line);
  }
  if (list != nullptr) libusb_free_device_list(list, 1);
  libusb_exit(ctx);
  return found;
}

LibusbTransport::LibusbTransport(const DeviceDescriptor& device) : device_(device) {
  device_.validate();
  description_ = device_.name + " usb " + usbId(device_.vendor_id, device_.product_id);
  in_queue_ = new InQueue();
  const int err = libusb_init(&context_);
  if (err != LIBUSB_SUCCESS) {
    delete in_queue_;
    throw Error(std::string("libusb_init failed (") + libusb_strerror(static_cast<libusb_error>(err)) +
                "): is /dev/bus/usb available to this process? (containers need it passed in)");
  }
  try {
    open();
  } catch (...) {
    close();
    libusb_exit(context_);
    delete in_queue_;
    throw;
  }
}

LibusbTransport::~LibusbTransport() {
  close();
  libusb_exit(context_);
  delete in_queue_;
}

void LibusbTransport::open() {
  libusb_device** list = nullptr;
  const ssize_t n = libusb_get_device_list(context_, &list);
  if (n < 0) throw Error(std::string("libusb_get_device_list failed: ") + libusb_strerror(static_cast<libusb_error>(n)));
  libusb_device* match = nullptr;
  std::string seen;
  for (ssize_t i = 0; i < n; ++i) {
    libusb_device_descriptor desc{};
    if (libusb_get_device_descriptor(list[i], &desc) != LIBUSB_SUCCESS) continue;
    char line[64];
    std::snprintf(line, sizeof line, "\n  bus %u addr %u %04x:%04x", libusb_get_bus_number(list[i]),
                  libusb_get_device_address(list[i]), desc.idVendor, desc.idProduct);
    seen += line;
    if (match == nullptr && desc.idVendor == device_.vendor_id && desc.idProduct == device_.product_id)
      match = list[i];
  }
  int err = LIBUSB_ERROR_NOT_FOUND;
  if (match != nullptr) {
    err = libusb_open(match, &handle_);
    char where[48];
    std::snprintf(where, sizeof where, " bus %u addr %u", libusb_get_bus_number(match), libusb_get_device_address(match));
    description_ = device_.name + " usb " + usbId(device_.vendor_id, device_.product_id) + where;
  }
  libusb_free_device_list(list, 1);
  if (match == nullptr)
    throw Error("no USB device " + usbId(device_.vendor_id, device_.product_id) + " (" + device_.name +
                ") found. USB devices present:" + (seen.empty() ? std::string(" none (is /dev/bus/usb visible to this process?)") : seen) +
                "\nCheck the cable and the board's power, and usb/vendor_id and usb/product_id in the device's parameter file.");
  if (err != LIBUSB_SUCCESS) { handle_ = nullptr; throw Error(libusbOpenAdvice(err, device_)); }

  // A kernel driver (e.g. cdc_acm on a board that also exposes a serial port) would own the
  // interface: let libusb detach it on claim and reattach it on release. Unsupported off Linux.
  libusb_set_auto_detach_kernel_driver(handle_, 1);
  err = libusb_claim_interface(handle_, device_.interface_number);
  if (err != LIBUSB_SUCCESS) throw Error(libusbOpenAdvice(err, device_));
  claimed_ = true;
  libusb_clear_halt(handle_, device_.endpoint_in);
  libusb_clear_halt(handle_, device_.endpoint_out);

  in_transfer_ = libusb_alloc_transfer(0);
  if (in_transfer_ == nullptr) throw Error("libusb_alloc_transfer failed (out of memory)");
  *in_queue_ = InQueue{};
  if (!armIn()) throw Error("cannot start reading from endpoint IN of " + description_);
}

bool LibusbTransport::armIn() noexcept {
  libusb_fill_bulk_transfer(in_transfer_, handle_, device_.endpoint_in, in_queue_->buffer.data(),
                            static_cast<int>(in_queue_->buffer.size()), onInComplete, in_queue_, 0);
  return libusb_submit_transfer(in_transfer_) == LIBUSB_SUCCESS;
}

void LibusbTransport::close() noexcept {
  if (in_transfer_ != nullptr) {
    // Cancel and wait for the callback: the transfer must not be freed while libusb owns it.
    if (libusb_cancel_transfer(in_transfer_) == LIBUSB_SUCCESS) {
      in_queue_->completed = false;
      timeval tv{0, 100000};
      for (int i = 0; i < 10 && !in_queue_->completed; ++i) {
        int done = 0;
        libusb_handle_events_timeout_completed(context_, &tv, &done);
      }
    }
    libusb_free_transfer(in_transfer_);
    in_transfer_ = nullptr;
  }
  if (handle_ != nullptr) {
    if (claimed_) libusb_release_interface(handle_, device_.interface_number);  // reattaches the kernel driver
    claimed_ = false;
    libusb_close(handle_);
    handle_ = nullptr;
  }
}

TransportStatus LibusbTransport::send(const std::uint8_t* data, std::size_t size, int timeout_us) noexcept {
  if (handle_ == nullptr || in_queue_->disconnected) return TransportStatus::kDisconnected;
  int sent = 0;
  // libusb's synchronous timeout is in ms and 0 means "forever": round up to at least 1 ms.
  const unsigned timeout_ms = static_cast<unsigned>(std::max(1, (timeout_us + 999) / 1000));
  const int err = libusb_bulk_transfer(handle_, device_.endpoint_out, const_cast<std::uint8_t*>(data),
                                       static_cast<int>(size), &sent, timeout_ms);
  if (err == LIBUSB_SUCCESS && sent != static_cast<int>(size)) return TransportStatus::kError;
  return fromLibusb(err);
}

TransportStatus LibusbTransport::receive(std::uint8_t* buffer, std::size_t capacity, std::size_t& received,
                                         int timeout_us) noexcept {
  received = 0;
  if (handle_ == nullptr) return TransportStatus::kDisconnected;
  InQueue& q = *in_queue_;
  if (q.count == 0) {
    // Let libusb run completions, waiting at most timeout_us (zero: just poll).
    in_queue_->completed = false;
    timeval tv{0, std::max(timeout_us, 0)};
    if (tv.tv_usec >= 1000000) { tv.tv_sec = tv.tv_usec / 1000000; tv.tv_usec %= 1000000; }
    const int err = libusb_handle_events_timeout_completed(context_, &tv, nullptr);
    if (err == LIBUSB_ERROR_NO_DEVICE) q.disconnected = true;
  }
  if (q.count > 0) {
    const std::size_t n = q.sizes[q.head];
    if (n > capacity) return TransportStatus::kError;
    std::memcpy(buffer, q.frames[q.head].data(), n);
    received = n;
    q.head = (q.head + 1) % InQueue::kFrames;
    --q.count;
    return TransportStatus::kOk;
  }
  if (q.disconnected) return TransportStatus::kDisconnected;
  if (q.error) return TransportStatus::kError;
  return TransportStatus::kTimeout;
}

bool LibusbTransport::reconnect() noexcept {
  close();
  try {
    open();
    return true;
  } catch (...) {
    close();
    return false;
  }
}

}  // namespace uhaptics
