#include "daemon/api/access.hpp"

#include <algorithm>

namespace calstand::daemon::api {

bool constant_time_equal(std::string_view a, std::string_view b) {
  // Compare over the longer length; a length difference makes the result false without an
  // early exit.
  const std::size_t n = std::max(a.size(), b.size());
  unsigned char diff = a.size() == b.size() ? 0 : 1;
  for (std::size_t i = 0; i < n; ++i) {
    const unsigned char x = i < a.size() ? static_cast<unsigned char>(a[i]) : 0;
    const unsigned char y = i < b.size() ? static_cast<unsigned char>(b[i]) : 0;
    diff |= static_cast<unsigned char>(x ^ y);
  }
  return diff == 0;
}

bool is_loopback_address(std::string_view host) {
  if (host == "localhost" || host == "::1" || host == "[::1]") return true;
  return host.substr(0, 4) == "127.";
}

bool bearer_token_accepted(std::string_view authorization_header, std::string_view token) {
  if (token.empty()) return true;
  constexpr std::string_view kScheme = "Bearer ";
  if (authorization_header.substr(0, kScheme.size()) != kScheme) return false;
  return constant_time_equal(authorization_header.substr(kScheme.size()), token);
}

std::string operator_name(std::string_view operator_header, std::string_view remote_addr) {
  std::string name(operator_header.empty() ? std::string_view("api")
                                           : operator_header.substr(0, 64));
  for (char& c : name) {
    if (c < 0x21 || c > 0x7e) c = '?';
  }
  return name + "@" + std::string(remote_addr);
}

}  // namespace calstand::daemon::api
