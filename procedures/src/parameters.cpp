// Parameter values: `--set NAME=VALUE` arguments and their checks against the declarations.
#include "parameters.hpp"

#include <fmt/format.h>

#include "references.hpp"
#include "static_checks.hpp"

namespace calstand::procedures {

std::string_view to_string(ParameterSpec::Type type) {
  switch (type) {
    case ParameterSpec::Type::kNumber:
      return "number";
    case ParameterSpec::Type::kString:
      return "string";
    case ParameterSpec::Type::kNumberList:
      return "number_list";
    case ParameterSpec::Type::kStringList:
      return "string_list";
  }
  return "?";
}

Overrides parse_overrides(const std::vector<std::string>& set_args) {
  Overrides out;
  for (const auto& arg : set_args) {
    const auto eq = arg.find('=');
    if (eq == std::string::npos) {
      throw core::InputError("--set " + arg, "expected NAME=VALUE, e.g. capture_s=30");
    }
    const std::string name = arg.substr(0, eq);
    if (name.empty()) throw core::InputError("--set " + arg, "the parameter name is missing");
    const std::string text = arg.substr(eq + 1);
    // JSON when it parses (numbers, lists, quoted strings); otherwise the text as a string, so
    // that `--set axis=outer` works without shell-quoted JSON quotes.
    nlohmann::json value = nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/false);
    if (value.is_discarded()) value = text;
    if (!out.emplace(name, std::move(value)).second) {
      throw core::InputError("--set " + name, "is given more than once");
    }
  }
  return out;
}

std::map<std::string, nlohmann::json> resolve_parameters(const Procedure& procedure,
                                                         const Overrides& overrides) {
  std::vector<Violation> violations;
  auto values = detail::resolve_parameters_collecting(procedure, overrides, violations);
  if (!violations.empty()) throw ProcedureError(procedure.file_name, std::move(violations));
  return values;
}

namespace detail {

std::map<std::string, nlohmann::json> resolve_parameters_collecting(const Procedure& procedure,
                                                                    const Overrides& overrides,
                                                                    std::vector<Violation>& out) {
  std::map<std::string, nlohmann::json> values = procedure.parameters;
  for (const auto& [name, value] : overrides) {
    const std::string path = "--set " + name;
    const auto spec = procedure.parameter_specs.find(name);
    if (spec == procedure.parameter_specs.end()) {
      std::string known;
      for (const auto& [n, s] : procedure.parameter_specs) known += (known.empty() ? "" : ", ") + n;
      out.push_back({path, fmt::format("{} is not a parameter of {} ({})", name, procedure.name,
                                       known.empty() ? "it has none" : "it has " + known)});
      continue;
    }
    auto bad = check_parameter_value(spec->second, value, path);
    if (bad.empty()) {
      values[name] = value;
    } else {
      out.insert(out.end(), bad.begin(), bad.end());
    }
  }
  return values;
}

}  // namespace detail
}  // namespace calstand::procedures
