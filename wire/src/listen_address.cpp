#include "wire/listen_address.hpp"

#include <fmt/format.h>

#include <charconv>

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

}  // namespace calstand::wire
