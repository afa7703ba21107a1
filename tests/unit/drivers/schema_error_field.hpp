#pragma once

// The field an input error names, for tests that check errors point at the right field whether
// the schema or a check in code found the mistake.

#include <string>

#include "core/error.hpp"
#include "core/json_schema.hpp"

namespace calstand::drivers::test {

/// where() for an error raised in code. For a schema error, the path of its last violation (a
/// failed oneOf first says so, then the problems of the closest form), extended by the property
/// that a "missing required property" or "unknown property" message names.
inline std::string error_field(const core::InputError& e) {
  const auto* schema_error = dynamic_cast<const core::SchemaError*>(&e);
  if (schema_error == nullptr || schema_error->violations().empty()) return e.where();
  const core::SchemaViolation& v = schema_error->violations().back();
  for (const std::string prefix : {"missing required property \"", "unknown property \""}) {
    if (v.message.rfind(prefix, 0) != 0) continue;
    const std::string key =
        v.message.substr(prefix.size(), v.message.find('"', prefix.size()) - prefix.size());
    return v.path.empty() ? key : v.path + "." + key;
  }
  return v.path;
}

}  // namespace calstand::drivers::test
