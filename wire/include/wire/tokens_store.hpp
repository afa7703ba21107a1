#pragma once
// The tokens file (`calstandd --tokens FILE`, schemas/tokens.schema.json) as the daemon reads
// it and `calstand token add | list | remove` edits it. An entry holds either its secret in
// plain text (`token`, as before: accepted, with a warning) or its id and salted hash (`id`,
// `hash`: the file never holds that secret).

#include <optional>
#include <string>
#include <vector>

namespace calstand::wire {

inline constexpr const char* kTokensFormat = "calstand-tokens/1";

struct TokenEntry {
  std::string name;
  std::string role;          ///< "read" or "operator"
  std::string plain_secret;  ///< non-empty: a plain-text entry (`token`)
  std::string id;            ///< hashed entries: the secret's public id (wire/token_hash.hpp)
  std::string hash;          ///< hashed entries: `$scrypt$...`
  bool hashed() const { return !hash.empty(); }
};

/// The entries of tokens file `path`, validated by schema (every violation named with its JSON
/// path), names, ids and secrets unique, hashes well formed. Throws core::InputError naming the
/// file. `missing_ok`: a file that does not exist reads as no entries.
std::vector<TokenEntry> read_tokens_file(const std::string& path, bool missing_ok = false);

/// Writes `entries` to `path` whole (a temporary renamed over it) with mode 0600. Throws
/// core::InputError naming the file.
void write_tokens_file(const std::string& path, const std::vector<TokenEntry>& entries);

/// Adds a hashed token `name` with `role` to `path` (made when missing) and returns its secret,
/// which is nowhere else: the caller prints it once. Throws core::InputError for a bad name or
/// role, or a name the file already has.
std::string add_hashed_token(const std::string& path, const std::string& name,
                             const std::string& role);

/// Removes token `name` from `path`. Throws core::InputError when the file has no such token,
/// or when it is the last one (a tokens file names at least one: remove the file and
/// calstandd's --tokens instead).
void remove_token(const std::string& path, const std::string& name);

}  // namespace calstand::wire
