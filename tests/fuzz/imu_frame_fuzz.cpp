// libFuzzer target: arbitrary bytes, split at fuzzer-chosen points, into the calstand IMU frame
// decoder. It must never crash, and its byte accounting must always hold.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <span>
#include <vector>

#include "drivers/imu_frame.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  // The first byte picks the chunk size, so splits of a frame across reads are explored too.
  const std::size_t chunk = 1 + data[0] % 64;
  calstand::drivers::CalstandFrameDecoder decoder(1 + (data[0] >> 6) * 1000);
  std::vector<calstand::core::ImuSample> out;
  for (std::size_t at = 1; at < size; at += chunk) {
    const std::size_t n = std::min(chunk, size - at);
    decoder.feed(std::span(data + at, n), out);
  }
  const auto& s = decoder.stats();
  const std::uint64_t accounted =
      s.frames * calstand::drivers::imu_frame::kFrameSize + s.garbage_bytes + decoder.buffered();
  if (accounted != s.bytes_fed || out.size() != s.frames) std::abort();
  return 0;
}
