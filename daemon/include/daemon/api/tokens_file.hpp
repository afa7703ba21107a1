#pragma once

#include <string>
#include <vector>

#include "daemon/api/access.hpp"

namespace calstand::daemon::api {

/// The name the single token of `--token-file` / `CALSTAND_TOKEN` is recorded under: it is an
/// operator token, as it was before named tokens existed.
inline constexpr const char* kLegacyTokenName = "operator";

/// Reads a tokens file (`calstandd --tokens FILE`, schemas/tokens.schema.json): named tokens
/// with their role. Throws core::InputError naming the file and the JSON path: a schema
/// violation (every one), a name or a secret given twice.
std::vector<NamedToken> load_tokens_file(const std::string& path);

/// Checks that no two tokens share a name or a secret (a shared secret would make the name
/// recorded with an action a guess). Throws core::InputError naming `where` and the name.
void check_unique_tokens(const std::vector<NamedToken>& tokens, const std::string& where);

}  // namespace calstand::daemon::api
