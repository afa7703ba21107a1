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

/// The definition `def_name` of `$defs` in the schema `file_name`, as a schema of its own (e.g.
/// the CAN signal map of station.schema.json, for a map in a file of its own, or a part of a
/// station built in code). Parsed once and cached. Thread safe. Throws std::logic_error when
/// the schema or the definition does not exist (a programming error).
const JsonSchema& schema_definition(std::string_view file_name, std::string_view def_name);

/// Validates `part`, the value at the JSON path `path` (e.g. "imus[0].connection"; empty for a
/// whole document) of a document read from `file_name` (empty when the document is not a file).
/// Throws SchemaError listing every violation, each with its full path (`path` followed by the
/// path within `part`), when `part` breaks `schema`.
void validate_part_or_throw(const JsonSchema& schema, const nlohmann::json& part,
                            const std::string& file_name, const std::string& path);

}  // namespace calstand::core
