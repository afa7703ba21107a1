#pragma once

#include <optional>
#include <string_view>
#include <vector>

#include "core/json_schema.hpp"

namespace calstand::core {

/// Text of a file of the repository's `schemas/` folder, compiled into the binary (generated
/// by cmake/CalstandEmbed.cmake), by file name, e.g. "station.schema.json".
std::optional<std::string_view> schema_text(std::string_view file_name);
std::vector<std::string_view> schema_text_names();

/// The parsed schema `file_name` of `schemas/`, parsed once and cached. Thread safe.
/// Throws std::logic_error when no such schema is compiled in (a programming error).
const JsonSchema& schema(std::string_view file_name);

}  // namespace calstand::core
