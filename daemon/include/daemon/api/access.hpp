#pragma once

#include <string>
#include <string_view>

namespace calstand::daemon::api {

/// True when `a` equals `b`, in a time that depends only on their lengths (so a client timing
/// the answers learns nothing about how much of a token it guessed right).
bool constant_time_equal(std::string_view a, std::string_view b);

/// True for an address that only this machine reaches: 127.0.0.0/8, ::1, "localhost".
/// 0.0.0.0, :: and every other address are beyond loopback.
bool is_loopback_address(std::string_view host);

/// Whether an `Authorization` header value carries `token` as `Bearer TOKEN` (constant time
/// in the token). An empty `token` means none is configured: everything is accepted.
bool bearer_token_accepted(std::string_view authorization_header, std::string_view token);

/// Who asked, for the event log: the `X-Calstand-Operator` header (printable ASCII, at most 64
/// characters; anything else is replaced by "?") or "api", then "@" and the client address.
std::string operator_name(std::string_view operator_header, std::string_view remote_addr);

}  // namespace calstand::daemon::api
