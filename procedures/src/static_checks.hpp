#pragma once

// Rules checked once a procedure has passed its schema, before any parameter value is known:
// parameter declarations, the form and scope of every reference, loop variable names, and the
// shape of rate steps. Each broken rule is appended as {JSON path, "VALUE RULE"}.

#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "procedures/procedure.hpp"

namespace calstand::procedures::detail {

/// The parameters of a schema-valid document, types inferred where not declared.
std::map<std::string, ParameterSpec> read_parameter_specs(const nlohmann::json& doc,
                                                          std::vector<Violation>& out);

/// Checks the steps of a schema-valid document against `specs`.
void check_steps(const nlohmann::json& doc, const std::map<std::string, ParameterSpec>& specs,
                 std::vector<Violation>& out);

/// The rule a value breaks for a parameter of `spec` (type, min, max), as {path suffix below
/// `path`, message}; empty when it is acceptable. Used for defaults and for overrides.
std::vector<Violation> check_parameter_value(const ParameterSpec& spec, const nlohmann::json& value,
                                             const std::string& path);

}  // namespace calstand::procedures::detail
