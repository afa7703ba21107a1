#pragma once

#include <string>
#include <string_view>
#include <utility>

namespace calstand::wire {

/// "HOST:PORT" ("127.0.0.1:8765", "[::1]:8765", "0.0.0.0:0") as host (without the IPv6
/// brackets) and port. Throws core::InputError naming `where` (the option it came from:
/// calstandd's `--listen`, a client's `--daemon`) when it is not of that form or the port is
/// not 0..65535.
std::pair<std::string, int> parse_listen_address(std::string_view text,
                                                 std::string_view where = "--listen");

}  // namespace calstand::wire
