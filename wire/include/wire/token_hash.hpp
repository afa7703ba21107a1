#pragma once
// Bearer tokens kept as salted hashes (`calstand token add`, calstandd --tokens): a stolen
// tokens file then lets nobody in. scrypt (RFC 7914) from OpenSSL's libcrypto, which calstand
// already links for TLS and hashing (docs/security.md says why scrypt and these parameters).

#include <string>
#include <string_view>

namespace calstand::wire {

/// A new secret, printed once by `calstand token add`: `ID.SECRET`, 16 hex digits of a public
/// id (which entry of the file to check, so a request costs one hash, not one per token) and
/// 64 hex digits (256 bits) from the operating system's random generator.
struct NewTokenSecret {
  std::string id;      ///< 16 lowercase hex digits
  std::string secret;  ///< the whole bearer token, `id` + "." + 64 hex digits
};
NewTokenSecret new_token_secret();

/// The id part of a presented bearer token (`ID.SECRET`), or empty when it has none.
std::string_view token_id_of(std::string_view presented);

/// The stored form of `secret`: `$scrypt$ln=15,r=8,p=1$SALT$KEY`, a fresh 16-byte salt and a
/// 32-byte key, both in lowercase hex. Takes about 0.1 s and 32 MiB (that is the point).
std::string hash_token_secret(std::string_view secret);

/// Whether `presented` hashes to `stored` (a hash_token_secret result); the keys are compared in
/// constant time. Throws core::InputError naming `where` when `stored` is not of that form.
bool token_secret_matches(std::string_view presented, std::string_view stored,
                          const std::string& where);

/// Throws core::InputError naming `where` unless `stored` is of hash_token_secret's form with
/// parameters this build accepts (so a bad file is refused when read, not at a request).
void check_token_hash(std::string_view stored, const std::string& where);

}  // namespace calstand::wire
