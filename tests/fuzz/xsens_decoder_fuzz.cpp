// libFuzzer target: arbitrary bytes, split at fuzzer-chosen points, into the Xsens MTi decoder
// (Xbus messages, MTData2 packets). It must never crash, its byte accounting must always hold,
// and every sample must come from a counted frame.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <span>
#include <vector>

#include "drivers/xsens_decoder.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  // The first byte picks the chunk size, so splits of a message across reads are explored too;
  // its top bit restarts the decoder half way, as a reader start after a flush does.
  const std::size_t chunk = 1 + data[0] % 64;
  const bool restart = (data[0] & 0x80) != 0;
  calstand::drivers::xsens::XsensDecoder decoder;
  std::vector<calstand::core::ImuSample> out;
  for (std::size_t at = 1; at < size; at += chunk) {
    if (restart && at >= size / 2 && at < size / 2 + chunk) decoder.restart();
    const std::size_t n = std::min(chunk, size - at);
    decoder.feed(std::span(data + at, n), out);
  }
  (void)decoder.take_device_reports();
  const auto& s = decoder.stats();
  const std::uint64_t accounted = s.message_bytes + s.garbage_bytes + s.start_bytes;
  // restart() drops what was buffered: the account holds up to that.
  if (!restart && accounted + decoder.buffered() != s.bytes_fed) std::abort();
  if (accounted + decoder.buffered() > s.bytes_fed) std::abort();
  if (out.size() != s.frames) std::abort();
  return 0;
}
