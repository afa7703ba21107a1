#include "daemon/api/access.hpp"

#include <algorithm>

#include "store/hash.hpp"
#include "wire/token_hash.hpp"

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

std::string_view bearer_of(std::string_view authorization_header) {
  constexpr std::string_view kScheme = "Bearer ";
  if (authorization_header.substr(0, kScheme.size()) != kScheme) return {};
  return authorization_header.substr(kScheme.size());
}

bool bearer_token_accepted(std::string_view authorization_header, std::string_view token) {
  if (token.empty()) return true;
  constexpr std::string_view kScheme = "Bearer ";
  if (authorization_header.substr(0, kScheme.size()) != kScheme) return false;
  return constant_time_equal(bearer_of(authorization_header), token);
}

std::string_view to_string(Role role) { return role == Role::kRead ? "read" : "operator"; }

Need AccessPolicy::need_of(std::string_view method, std::string_view path) const {
  if (method != "GET" && method != "HEAD") return Need::kOperator;
  // The console's page and scripts hold no station data, and a browser must load them before
  // anyone can type a token into them.
  if (path == "/" || path.substr(0, 9) == "/console/") return Need::kNothing;
  return Need::kRead;
}

const NamedToken* AccessPolicy::match(std::string_view presented) const {
  if (presented.empty()) return nullptr;
  const NamedToken* found = nullptr;
  for (const auto& t : tokens) {
    // No early exit: every secret is compared whichever matched.
    if (!t.hashed() && constant_time_equal(presented, t.secret) && found == nullptr) found = &t;
  }
  if (found != nullptr) return found;
  const std::string_view id = wire::token_id_of(presented);
  if (id.empty()) return nullptr;
  const std::string digest = store::sha256_hex(presented);
  {
    std::lock_guard lock(verified->mutex);
    const auto known = verified->token_of_digest.find(digest);
    if (known != verified->token_of_digest.end()) return &tokens[known->second];
  }
  for (std::size_t i = 0; i < tokens.size(); ++i) {
    const NamedToken& t = tokens[i];
    if (!t.hashed() || t.id != id) continue;
    bool matches = false;
    {
      std::lock_guard hashing(verified->hashing);
      matches = wire::token_secret_matches(presented, t.hash, "token '" + t.name + "'");
    }
    if (!matches) return nullptr;
    std::lock_guard lock(verified->mutex);
    verified->token_of_digest.emplace(digest, i);
    return &t;
  }
  return nullptr;
}

AccessDecision check_access(const AccessPolicy& policy, std::string_view method,
                            std::string_view path, std::string_view presented) {
  AccessDecision d;
  d.caller = policy.match(presented);
  const Need need = policy.need_of(method, path);
  const bool token_needed = (need == Need::kOperator && !policy.tokens.empty()) ||
                            (need == Need::kRead && policy.reads_need_token);
  if (!token_needed) return d;
  if (d.caller == nullptr) {
    d.status = 401;
    d.why = presented.empty() ? "a bearer token is required for this request"
                              : "the bearer token is not one this daemon accepts";
    return d;
  }
  if (need == Need::kOperator && d.caller->role != Role::kOperator) {
    d.status = 403;
    d.why =
        "the token '" + d.caller->name + "' may only read; this request needs an operator token";
  }
  return d;
}

std::string operator_name(std::string_view operator_header, std::string_view remote_addr,
                          std::string_view token_name) {
  std::string name(operator_header.empty() ? std::string_view("api")
                                           : operator_header.substr(0, 64));
  for (char& c : name) {
    if (c < 0x21 || c > 0x7e) c = '?';
  }
  name += "@" + std::string(remote_addr);
  if (!token_name.empty()) name += " (token " + std::string(token_name) + ")";
  return name;
}

}  // namespace calstand::daemon::api
