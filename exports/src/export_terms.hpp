#pragma once
// What the exporters (export_*.cpp) share: a calibration record's parameters sorted into the
// matrices and polynomials of the measurement model (error-model.md), in the contract's units,
// and the warnings every target needs (parameters it cannot represent, parameters the record
// did not determine). Private to the analysis library.

#include <Eigen/Core>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "solver/calibration_record.hpp"
#include "solver/model.hpp"

namespace calstand::analysis::exporting {

inline constexpr double kRadPerDeg = 3.14159265358979323846 / 180.0;
inline constexpr double kStandardGravity = 9.80665;  ///< g0 of the contract [m/s^2]

/// One triad's part of the measurement model, contract units: deg/s (gyro) or m/s^2 (accel).
///   measured = K truth + bias + sum_k temp_bias[k-1] dT^k + ...,   K = I + 1e-6 diag(s) + M
struct SensorTerms {
  Eigen::Vector3d bias = Eigen::Vector3d::Zero();
  Eigen::Vector3d scale_ppm = Eigen::Vector3d::Zero();
  Eigen::Matrix3d misalignment = Eigen::Matrix3d::Zero();  ///< [rad], M[i][j]: truth j into i
  /// temp_bias[k - 1]: the coefficients of dT^k per axis [unit/degC^k]; empty without the term.
  std::vector<Eigen::Vector3d> temp_bias;

  /// K = I + 1e-6 diag(scale_ppm) + misalignment.
  Eigen::Matrix3d scale_matrix() const;
  /// sum_k temp_bias[k-1] dT^k: the bias' change at dT = T - T_ref from the bias at T_ref.
  Eigen::Vector3d temp_offset(double dT) const;
};

/// A record's parameters by their place in the model. Parameters the record did not determine
/// are zero (as `calstand apply` uses them).
struct RecordTerms {
  SensorTerms gyro;                                         ///< deg/s
  SensorTerms accel;                                        ///< m/s^2
  Eigen::Matrix3d g_sensitivity = Eigen::Matrix3d::Zero();  ///< [(deg/s)/g], G[i][j]: f_j into i
  double temperature_ref_c = 25.0;
  std::optional<double> valid_min_c;  ///< none for a recording without temperature
  std::optional<double> valid_max_c;
  /// The model's parameters (names, units, terms) and their values, in the model's order.
  std::vector<solver::ParameterInfo> parameters;
  std::vector<double> values;
};

/// Sorts the calibration's parameters. Custom terms and terms without a place above
/// (asymmetry, quadratic, temp_scale, lever arm, table tilt) stay only in `parameters`.
RecordTerms record_terms(const solver::Calibration& calibration);

/// The catalogue name of a parameter's term: "gyro_temp_bias" for "gyro_temp_bias:3", the
/// custom name for a custom term.
std::string term_base_name(const solver::ParameterInfo& parameter);

/// Names grouped by term, for one sentence: "gyro_misalignment.xy .xz, gyro_scale.x".
std::string join_parameter_names(const std::vector<std::string>& names);

/// The warning for the model's parameters that `kept` says the target has no place for (custom
/// terms included), or none when every parameter has one. `target` names the target ("PX4").
/// Station terms (table_tilt) are named apart: they describe the table, not the unit.
std::optional<std::string> left_out_warning(const RecordTerms& terms,
                                            const std::function<bool(std::string_view)>& kept,
                                            std::string_view target);

/// The warning for the model parameters the record lists as not determined (written as 0), or
/// none.
std::optional<std::string> undetermined_warning(const solver::Calibration& calibration);

/// Throws core::InputError naming the term and `format` when a temperature polynomial of the
/// record is of higher order than `max_order` (PX4 and ArduPilot stop at 3).
void refuse_temp_order_above(const RecordTerms& terms, int max_order, std::string_view format);

/// `value` with 9 significant digits: enough to give back any float32 exactly (PX4 and
/// ArduPilot keep their parameters as float32).
std::string float32_text(double value);

/// One line of comments naming the record: device, model, serial, runs, created, software.
std::string record_identity(const solver::Calibration& calibration);

}  // namespace calstand::analysis::exporting
