#pragma once
// An acceptance specification (schemas/acceptance.schema.json, calstand-acceptance/1): read,
// checked against its schema, then by hand for what a schema cannot say (a limit's unit against
// the units of the names its pattern matches, a pattern that matches nothing, min above max).

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "factory/decision_rule.hpp"

namespace calstand::analysis {

inline constexpr const char* kAcceptanceFormat = "calstand-acceptance/1";
/// The coverage factor of the guard band when a specification gives none.
inline constexpr double kDefaultCoverageFactor = 2.0;

/// What a limit is on.
enum class LimitKind {
  kParameter,         ///< error-model parameters, by pattern
  kNoise,             ///< noise figures of the record's noise block, by pattern
  kFit,               ///< a fit figure (chi2_dof, rms_gyro, ...)
  kTemperatureRange,  ///< the record's valid temperature range must cover [min, max]
};

/// "parameter", "noise", "fit" or "temperature_range_c" (the key that introduces the limit).
std::string_view to_string(LimitKind kind);

/// One entry of `limits` (or of `validation.limits`).
struct AcceptanceLimit {
  std::string where;  ///< its place in the file, e.g. "limits[2]", for messages
  LimitKind kind = LimitKind::kParameter;
  std::string pattern;              ///< kParameter, kNoise: a name or `*` pattern; kFit: the figure
  std::string unit;                 ///< the unit of every name matched ("" for chi2_dof)
  Bounds value;                     ///< on the value (may be empty for a limit on the sigma alone)
  std::optional<double> max_sigma;  ///< kParameter: on the 1-sigma uncertainty [unit]
  double temperature_min_c = 0.0;   ///< kTemperatureRange [degC]
  double temperature_max_c = 0.0;
};

/// The validation run part: terms to fit to the corrected run (empty: the record's model) and
/// the limits what remains must keep (kParameter and kFit only).
struct ValidationSpec {
  std::vector<std::string> model;
  std::vector<AcceptanceLimit> limits;
};

/// A specification ready to judge records against.
struct AcceptanceSpec {
  std::string file;  ///< where it was read from (messages, output)
  std::string name;
  std::string sha256;  ///< of the file's bytes as read
  double k = kDefaultCoverageFactor;
  std::vector<AcceptanceLimit> limits;
  std::optional<ValidationSpec> validation;
};

/// Parses specification text read from `file_name`. Throws core::InputError naming the file
/// and line for bad JSON, core::SchemaError listing every violation of the schema, and then
/// core::SchemaError listing every hand-checked violation, each by its path (e.g.
/// `limits[0].unit: "deg/h" is not the unit of gyro_bias.* (deg/s)`).
AcceptanceSpec parse_acceptance_spec(std::string_view text, const std::string& file_name);

/// Reads and parses the file at `path` (parse_acceptance_spec(); sha256 of its bytes). Throws
/// core::InputError naming the path when it cannot be read.
AcceptanceSpec read_acceptance_spec(const std::string& path);

/// {"name", "file", "sha256", "k"}: the specification as the output names it.
nlohmann::json spec_json(const AcceptanceSpec& spec);

}  // namespace calstand::analysis
