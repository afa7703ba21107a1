#include "drivers/device_dialogue.hpp"

#include <fmt/format.h>

#include <array>

#include "drivers/fd_io.hpp"
#include "drivers/imu_wire_format.hpp"

namespace calstand::drivers {

std::optional<std::vector<std::uint8_t>> read_reply(ByteTransport& link,
                                                    const ReplyFinder& find_reply,
                                                    std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  std::vector<std::uint8_t> received;
  std::array<std::uint8_t, 4096> chunk{};
  for (;;) {
    const auto left = std::chrono::milliseconds(remaining_ms(deadline));
    const IoResult r = link.read(chunk, left);
    if (!r.ok()) throw DeviceConfigError(r.error);
    received.insert(received.end(), chunk.begin(), chunk.begin() + r.bytes);
    if (r.bytes > 0) {
      if (auto reply = find_reply(received)) return reply;
    }
    if (left.count() == 0) return std::nullopt;
    // A stream at 2 kHz fills a megabyte in a few seconds; a reply is near the newest bytes.
    if (received.size() > (1u << 20)) received.erase(received.begin(), received.end() - 4096);
  }
}

std::vector<std::uint8_t> request_reply(ByteTransport& link, std::span<const std::uint8_t> request,
                                        const ReplyFinder& find_reply,
                                        std::chrono::milliseconds timeout, int attempts,
                                        const std::string& what) {
  for (int attempt = 0; attempt < attempts; ++attempt) {
    const IoResult w = link.write(request, timeout);
    if (!w.ok()) throw DeviceConfigError(fmt::format("sending {}: {}", what, w.error));
    if (auto reply = read_reply(link, find_reply, timeout)) return std::move(*reply);
  }
  throw DeviceConfigError(fmt::format("no reply to {} within {} ms ({} attempt{})", what,
                                      timeout.count(), attempts, attempts == 1 ? "" : "s"));
}

}  // namespace calstand::drivers
