// libFuzzer target: arbitrary bytes, split at fuzzer-chosen points, into the Epson burst decoder
// (docs/protocols.md, "Epson M-G3xx/G5xx"). It must never crash, its byte accounting must hold,
// and device time may go back only where it reported a device restart.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <span>
#include <vector>

#include "drivers/epson_wire.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace calstand::drivers;
  if (size == 0) return 0;
  // The first byte picks the chunk size, the width and the counter's step.
  const std::size_t chunk = 1 + data[0] % 48;
  WireFormatSettings settings;
  settings.sample_rate_hz = 100;
  settings.options = {{"model", "G366PDG0"},
                      {"width_bits", (data[0] & 0x40) != 0 ? 16 : 32},
                      {"count_step", (data[0] & 0x80) != 0 ? "output" : "base"}};
  epson::Decoder decoder(epson::Options::from_settings(settings));
  std::vector<calstand::core::ImuSample> out;
  for (std::size_t at = 1; at < size; at += chunk) {
    const std::size_t n = std::min(chunk, size - at);
    decoder.feed(std::span(data + at, n), out);
  }
  auto c = decoder.counters();
  const std::uint64_t frame_size = epson::burst_size(settings.options["width_bits"].get<int>());
  if (c["frames"] * frame_size + c["garbage_bytes"] + c["start_bytes"] + decoder.buffered() !=
      c["bytes_fed"]) {
    std::abort();
  }
  if (out.size() != c["frames"]) std::abort();
  std::uint64_t backwards = 0;
  for (std::size_t i = 1; i < out.size(); ++i) {
    if (out[i].device_time_s < out[i - 1].device_time_s) ++backwards;
  }
  if (backwards > c["device_restarts"]) std::abort();
  return 0;
}
