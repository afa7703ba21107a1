// libFuzzer target: arbitrary bytes, split at fuzzer-chosen points, into the VectorNav VN-100
// decoder (binary messages with ASCII messages among them). It must never crash, and its byte
// accounting must always hold.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <span>
#include <vector>

#include "drivers/vectornav_decoder.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  // The first byte picks the chunk size and which outputs the decoder prefers.
  const std::size_t chunk = 1 + data[0] % 64;
  calstand::drivers::vectornav::VectornavDecoder decoder(100.0 * (1 + (data[0] >> 7)),
                                                         (data[0] & 0x40) != 0);
  std::vector<calstand::core::ImuSample> out;
  for (std::size_t at = 1; at < size; at += chunk) {
    const std::size_t n = std::min(chunk, size - at);
    decoder.feed(std::span(data + at, n), out);
    (void)decoder.take_device_reports();
  }
  const auto& s = decoder.stats();
  const std::uint64_t accounted =
      s.frame_bytes + s.ascii_bytes + s.garbage_bytes + s.start_bytes + decoder.buffered();
  if (accounted != s.bytes_fed || out.size() + s.incomplete_frames != s.frames) std::abort();
  return 0;
}
