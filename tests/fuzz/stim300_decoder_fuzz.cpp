// libFuzzer target: arbitrary bytes, split at fuzzer-chosen points, into the STIM300 datagram
// decoder, under the option combinations that change its framing. It must never crash, and its
// byte accounting must always hold.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <span>
#include <vector>

#include "drivers/stim300_decoder.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace calstand::drivers::stim300;
  if (size < 2) return 0;
  // First byte: chunk size; second: options (termination, locked identifier, output units).
  const std::size_t chunk = 1 + data[0] % 64;
  Stim300Options options;
  switch (data[1] % 3) {
    case 1:
      options.termination = true;
      break;
    case 2:
      options.termination = false;
      break;
    default:
      break;
  }
  if (data[1] & 0x04) options.datagram = normal_datagram_ids()[(data[1] >> 3) % 8];
  if (data[1] & 0x40) options.gyro_output = GyroOutput::kIncrement;
  if (data[1] & 0x80) options.accel_output = AccelOutput::kIncrement;
  Stim300Decoder decoder(options, 2000.0);
  std::vector<calstand::core::ImuSample> out;
  for (std::size_t at = 2; at < size; at += chunk) {
    const std::size_t n = std::min(chunk, size - at);
    decoder.feed(std::span(data + at, n), out);
    if (at % 7 == 0) decoder.restart();
  }
  decoder.take_device_reports();
  const auto& s = decoder.stats();
  const std::uint64_t accounted =
      s.frame_bytes + s.garbage_bytes + s.start_bytes + decoder.buffered();
  if (accounted != s.bytes_fed || out.size() != s.frames) std::abort();
  return 0;
}
