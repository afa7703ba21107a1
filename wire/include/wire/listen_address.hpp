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

/// Where a client finds calstandd: `HOST:PORT`, `http://HOST:PORT` or `https://HOST:PORT`.
struct DaemonEndpoint {
  bool tls = false;  ///< https
  std::string host;  ///< without IPv6 brackets
  int port = 0;
  /// `http[s]://HOST:PORT` (IPv6 hosts in brackets), as HTTP clients take it.
  std::string url() const;
};

/// A client's `--daemon`: HOST:PORT as parse_listen_address() reads it, optionally after
/// `http://` or `https://` (plain HOST:PORT is http unless `tls_by_default`, e.g. when a CA
/// file was given). Throws core::InputError naming `where` for any other scheme or shape.
DaemonEndpoint parse_daemon_address(std::string_view text, std::string_view where,
                                    bool tls_by_default = false);

}  // namespace calstand::wire
