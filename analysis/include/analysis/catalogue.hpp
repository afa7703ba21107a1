#pragma once
// The model's building blocks for a user picking them (GET /catalogue): the error terms of the
// contract with their effect in words, and the signals custom terms may use.

#include <nlohmann/json.hpp>
#include <string_view>
#include <vector>

namespace calstand::analysis {

/// A signal of custom-term expressions (error-model.md, "Signals").
struct CustomSignal {
  std::string_view name;  ///< as solver::signal_names()
  std::string_view unit;
  std::string_view meaning;
};

/// Every name of solver::signal_names(), in its order, with unit and meaning. Throws
/// std::logic_error when the solver knows a signal this table does not describe (a new signal
/// must be described here).
std::vector<CustomSignal> custom_signals();

/// {"terms": [{"name", "sensor": "gyro"|"accel"|"both", "unit", "ordered", "effect"}...],
///  "signals": [{"name", "unit", "meaning"}...]}: the catalogue in the contract's order;
/// "ordered" terms take a polynomial order (gyro_temp_bias:2); a reference term (earth_rate,
/// table_tilt) is "both".
nlohmann::json catalogue_json();

}  // namespace calstand::analysis
