#pragma once

#include <string>
#include <string_view>

namespace calstand::store {

/// SHA-256 of `data` as 64 lowercase hex digits (OpenSSL). Identifies a procedure's exact text
/// in runs.procedure_sha256.
std::string sha256_hex(std::string_view data);

}  // namespace calstand::store
