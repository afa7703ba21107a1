#include "wire/listen_address.hpp"

#include <fmt/format.h>

#include <charconv>
#include <tuple>

#include "core/error.hpp"

namespace calstand::wire {

std::pair<std::string, int> parse_listen_address(std::string_view text, std::string_view where) {
  const auto colon = text.rfind(':');
  if (colon == std::string_view::npos || colon == 0 || colon + 1 == text.size()) {
    throw core::InputError(std::string(where), fmt::format("'{}' is not HOST:PORT", text));
  }
  std::string_view host = text.substr(0, colon);
  if (host.size() > 2 && host.front() == '[' && host.back() == ']')
    host = host.substr(1, host.size() - 2);
  const std::string_view port_text = text.substr(colon + 1);
  int port = 0;
  const auto [end, ec] =
      std::from_chars(port_text.data(), port_text.data() + port_text.size(), port);
  if (ec != std::errc() || end != port_text.data() + port_text.size() || port < 0 || port > 65535) {
    throw core::InputError(std::string(where),
                           fmt::format("'{}' is not a port (0..65535)", port_text));
  }
  return {std::string(host), port};
}

std::string DaemonEndpoint::url() const {
  const bool v6 = host.find(':') != std::string::npos;
  return fmt::format("{}://{}{}{}:{}", tls ? "https" : "http", v6 ? "[" : "", host, v6 ? "]" : "",
                     port);
}

DaemonEndpoint parse_daemon_address(std::string_view text, std::string_view where,
                                    bool tls_by_default) {
  DaemonEndpoint out;
  out.tls = tls_by_default;
  if (const auto scheme_end = text.find("://"); scheme_end != std::string_view::npos) {
    const std::string_view scheme = text.substr(0, scheme_end);
    if (scheme != "http" && scheme != "https") {
      throw core::InputError(std::string(where),
                             fmt::format("'{}': the scheme must be http or https", text));
    }
    out.tls = scheme == "https";
    text = text.substr(scheme_end + 3);
    if (!text.empty() && text.back() == '/') text.remove_suffix(1);
  }
  std::tie(out.host, out.port) = parse_listen_address(text, where);
  return out;
}

}  // namespace calstand::wire
