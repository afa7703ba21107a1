#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "drivers/serial_port.hpp"

namespace calstand::drivers {

/// Recognises a reply in the bytes received since a request was sent (the device may be
/// streaming measurements around it): the reply's bytes once it is complete, nothing yet
/// otherwise. Called again with the longer buffer as bytes arrive.
using ReplyFinder =
    std::function<std::optional<std::vector<std::uint8_t>>(std::span<const std::uint8_t> received)>;

/// Reads `link` until `find_reply` recognises a reply or `timeout` passes (nothing then).
/// Throws DeviceConfigError (imu_wire_format.hpp) when the link fails.
std::optional<std::vector<std::uint8_t>> read_reply(ByteTransport& link,
                                                    const ReplyFinder& find_reply,
                                                    std::chrono::milliseconds timeout);

/// Sends `request` and waits for its reply, up to `attempts` times (a device busy with a
/// reset, or a byte lost on the line, gets another chance). Throws DeviceConfigError
/// "no reply to WHAT within T ms (N attempts)" when none comes, or when the link fails.
std::vector<std::uint8_t> request_reply(ByteTransport& link, std::span<const std::uint8_t> request,
                                        const ReplyFinder& find_reply,
                                        std::chrono::milliseconds timeout, int attempts,
                                        const std::string& what);

}  // namespace calstand::drivers
