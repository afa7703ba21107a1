#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace calstand::core {

/// Which measurement an error term acts on.
enum class TermSensor { kGyro, kAccel, kReference };

/// One term of the error-model contract (../shared/docs/error-model.md): its name, parameter
/// components, unit and the physical effect in words. This table is the single source of the
/// names; the simulator reads truth files with it and the solver builds its regressors on it.
struct ErrorTermInfo {
  std::string_view name;  ///< e.g. "gyro_misalignment"
  TermSensor sensor;
  std::vector<std::string_view> components;  ///< e.g. {"xy","xz","yx","yz","zx","zy"}
  std::string_view unit;                     ///< unit of every parameter, as in the contract
  std::string_view effect;                   ///< the physical effect, one sentence
  bool polynomial_order = false;             ///< true for `*_temp_bias[:N]` (components x1..zN)
};

/// Every catalogue term, in the contract's order.
const std::vector<ErrorTermInfo>& error_term_catalogue();

/// The term named `name` (without ":N"), or nullptr.
const ErrorTermInfo* find_error_term(std::string_view name);

/// A parsed full parameter name `<term>.<component>`, e.g. "gyro_temp_bias.y2".
struct ParameterName {
  const ErrorTermInfo* term = nullptr;
  std::string component;  ///< "y2" in the example
  int axis = -1;          ///< 0..2 for per-axis components (x, y, z), else -1
  int second_axis = -1;   ///< coupled axis for misalignment / g-sensitivity components
  int order = 0;          ///< power of dT for temp_bias components, else 0
};

/// Parses and checks a full parameter name against the catalogue; std::nullopt with `why`
/// filled in (e.g. `unknown component "xx" of gyro_misalignment (diagonal is not a parameter)`)
/// when it is not one.
std::optional<ParameterName> parse_parameter_name(std::string_view full_name, std::string* why);

/// Full parameter names of a term, `order` applying to polynomial terms (x1 y1 z1 ... zN).
std::vector<std::string> parameter_names(const ErrorTermInfo& term, int order = 1);

}  // namespace calstand::core
