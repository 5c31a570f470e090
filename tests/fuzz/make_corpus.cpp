// Writes the fuzzer's seed corpus: one valid frame of every message type and channel count, made by
// the encoder, so the fuzzer starts from inputs that pass the CRC and explores field checks.
// Usage: uhaptics-wire-corpus <directory>
#include <cstdio>
#include <string>

#include "uhaptics/protocol/wire_protocol.hpp"

using namespace uhaptics::wire;

namespace {
int written = 0;
bool write(const std::string& dir, const Frame& f) {
  std::uint8_t buf[kMaxFrameSize];
  const std::size_t n = encode(f, buf, sizeof buf);
  if (n == 0) return false;
  const std::string path = dir + "/seed_" + std::to_string(written++) + ".bin";
  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (file == nullptr) return false;
  const bool ok = std::fwrite(buf, 1, n, file) == n;
  return std::fclose(file) == 0 && ok;
}
}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s <corpus-directory>\n", argv[0]);
    return 2;
  }
  const std::string dir = argv[1];
  bool ok = write(dir, makeHello(DeviceType{1}, 0, 0x12345678));
  Frame f;
  f.type = MessageType::kDeviceInfo;
  f.device = DeviceType{2};
  f.info = DeviceInfo{1, 1, 1, 6, 6, 1000, 0x00010000, 0x12345678};
  ok = ok && write(dir, f);
  f = Frame{};
  f.type = MessageType::kConfigure;
  f.configure.watchdog_timeout_us = 5000;
  ok = ok && write(dir, f);
  f = Frame{};
  f.type = MessageType::kAck;
  f.ack = Ack{1, MessageType::kConfigure, BoardError::kNone};
  ok = ok && write(dir, f);
  const double efforts[kMaxChannels] = {0.1, -0.2, 0.3, -0.4, 1.0, -1.0, 2.0, -2.0};
  for (int n = 0; n <= kMaxChannels; ++n) {
    ok = ok && write(dir, makeCommand(DeviceType{3}, static_cast<std::uint16_t>(n), CommandMode::kEffort, efforts, n));
    f = Frame{};
    f.type = MessageType::kState;
    f.device = DeviceType{2};
    f.sequence = static_cast<std::uint16_t>(1000 + n);
    f.state.status = status::kConfigured | status::kOutputsEnabled;
    f.state.count = static_cast<std::uint8_t>(n);
    for (int i = 0; i < n; ++i) {
      f.state.position[i] = 0.1f * static_cast<float>(i);
      f.state.sample_time_us[i] = 1000u * static_cast<std::uint32_t>(i);
    }
    ok = ok && write(dir, f);
  }
  ok = ok && write(dir, makeCommand(DeviceType{1}, 7, CommandMode::kZero, efforts, 1));
  if (!ok) {
    std::fprintf(stderr, "uhaptics-wire-corpus: could not write the corpus into %s\n", dir.c_str());
    return 1;
  }
  std::printf("wrote %d seed frames into %s\n", written, dir.c_str());
  return 0;
}
