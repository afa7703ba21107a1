#pragma once
// What an acceptance specification can put a limit on, by name: the error-model parameters of
// the catalogue (core/error_terms.hpp), the noise figures of a record's `noise` block, and the
// fit figures of its `fit` block, each with its unit; and the `*` patterns over those names.

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace calstand::analysis {

/// A name a limit may match, with the unit its values are in.
struct NamedQuantity {
  std::string name;  ///< e.g. "gyro_bias.x", "gyro_arw.z", "chi2_dof"
  std::string unit;  ///< e.g. "deg/s"; "" for a pure number (chi2/dof)
};

/// True when `name` matches `pattern`, in which `*` stands for any run of characters (also
/// none, also dots) and every other character for itself: `gyro_bias.*`, `*_misalignment.*`.
bool glob_match(std::string_view pattern, std::string_view name);

/// Every parameter name of the catalogue with its unit (polynomial terms up to order 9:
/// `gyro_temp_bias.x1` ... `.z9`), in the catalogue's order. Custom terms have no fixed names
/// and are not among them.
const std::vector<NamedQuantity>& catalogue_parameters();

/// A noise figure a specification names, e.g. `gyro_arw.x`: `<short name>.<axis>`, read from a
/// record's noise block (analysis::calibration_noise_figures()) as the figure `figure` of
/// channel g<axis> or a<axis>.
struct NoiseName {
  std::string_view name;    ///< e.g. "gyro_arw"
  std::string_view figure;  ///< the datasheet figure's name, e.g. "angle_random_walk"
  bool gyro = true;
  std::string_view unit;  ///< as solver::datasheet_figures() gives it, e.g. "deg/sqrt(h)"
  std::string_view meaning;
};

/// The noise names, gyro first (docs/acceptance.md lists them).
const std::vector<NoiseName>& noise_names();

/// Every noise figure name with its unit, per axis: `gyro_arw.x` ... `accel_quantization.z`.
const std::vector<NamedQuantity>& noise_quantities();

/// The fit figures: chi2_dof (no unit), rms_gyro [deg/s], rms_accel [m/s^2] of a table fit,
/// rms_norm [m/s^2] and rms_turn [deg] of a fit without a table.
const std::vector<NamedQuantity>& fit_quantities();

/// A value a record gives for a name, with its 1-sigma uncertainty when it gives one.
struct RecordValue {
  std::string name;
  std::string unit;
  double value = 0.0;
  std::optional<double> sigma;
  std::string note;     ///< e.g. "not resolved by the noise fit", or why it has no value
  bool present = true;  ///< false: the record names it but has no value (not determined)
};

/// The parameters of a calibration record (schemas/calibration.schema.json): the fitted ones
/// with value and sigma, then the ones its runs could not determine (present = false, the
/// reason as note).
std::vector<RecordValue> record_parameters(const nlohmann::json& record);

/// The noise figures of a record's noise block under their noise names (sigma absent for
/// figures read off the Allan curve); empty when the record has no noise block.
std::vector<RecordValue> record_noise(const nlohmann::json& record);

/// The fit figures a record has (a figure that is null or absent is not listed).
std::vector<RecordValue> record_fit(const nlohmann::json& record);

}  // namespace calstand::analysis
