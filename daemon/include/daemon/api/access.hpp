#pragma once

#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <vector>

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

/// What a token may do: `kRead` reads everything (runs, station, stream, reports, exports);
/// `kOperator` also acts (every request that is not a GET or HEAD).
enum class Role { kRead, kOperator };
std::string_view to_string(Role role);

/// One bearer token the daemon accepts. `name` is recorded with every action taken with it.
/// Either `secret` in plain text, or (a hashed token of `calstand token add`) its public `id`
/// and salted `hash` (wire/token_hash.hpp): the daemon never holds that secret.
struct NamedToken {
  std::string name;
  Role role = Role::kOperator;
  std::string secret;
  std::string id{};  // braces: tokens listed as {name, role, secret} stay warning-free
  std::string hash{};
  bool hashed() const { return !hash.empty(); }
};

/// The hashed tokens' secrets a daemon has verified, by their SHA-256: scrypt is paid once per
/// secret, not per request. Shared by the copies of one AccessPolicy.
struct VerifiedSecrets {
  std::mutex mutex;
  std::map<std::string, std::size_t> token_of_digest;  ///< index into AccessPolicy::tokens
  std::mutex hashing;  ///< one scrypt at a time: 32 MiB each, however many clients knock
};

/// What a request needs: nothing (the console's own files, which hold no station data), a
/// token of any role (reads, when they need one), or an operator token.
enum class Need { kNothing, kRead, kOperator };

/// Who may do what on one daemon. Thread safe to read (immutable once the server runs).
struct AccessPolicy {
  /// Every token accepted; empty: none configured (the daemon then listens on loopback only
  /// and everything is open, as before tokens existed).
  std::vector<NamedToken> tokens;
  /// Reads need a token too: set when the daemon listens beyond loopback.
  bool reads_need_token = false;
  /// Filled by match(); mutable state behind a pointer, so the policy reads as immutable.
  std::shared_ptr<VerifiedSecrets> verified = std::make_shared<VerifiedSecrets>();

  /// What `method` on `path` needs: GET/HEAD of `/` and `/console/...` nothing; any other GET
  /// or HEAD a read (a token of any role when reads_need_token); anything else an operator
  /// token (when any token is configured).
  Need need_of(std::string_view method, std::string_view path) const;
  /// The token whose secret is `presented`, or nullptr. Every plain secret is compared, each in
  /// constant time, so the time taken says nothing about which one nearly matched; a hashed
  /// token is found by the id its secret starts with and checked by its hash (the first time:
  /// then remembered).
  const NamedToken* match(std::string_view presented) const;
};

/// The outcome of checking one request: `status` 0 when it may go on, else 401 (no token, or
/// one the daemon does not know) or 403 (a read token asking to act), with `why`. `caller` is
/// the token presented when it matched, whether or not the request needed it.
struct AccessDecision {
  int status = 0;
  std::string why;
  const NamedToken* caller = nullptr;
};

/// Checks a request presenting `presented` (the bearer token, empty when none) against
/// `policy`.
AccessDecision check_access(const AccessPolicy& policy, std::string_view method,
                            std::string_view path, std::string_view presented);

/// The token of an `Authorization: Bearer TOKEN` header value; empty for anything else.
std::string_view bearer_of(std::string_view authorization_header);

/// Who asked, for the event log: the `X-Calstand-Operator` header (printable ASCII, at most 64
/// characters; anything else is replaced by "?") or "api", then "@" and the client address,
/// then " (token NAME)" when a token vouched for the request: the header is the client's
/// word, the token's name is what the daemon checked.
std::string operator_name(std::string_view operator_header, std::string_view remote_addr,
                          std::string_view token_name = {});

}  // namespace calstand::daemon::api
