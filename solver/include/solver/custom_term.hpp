#pragma once

#include <Eigen/Core>
#include <array>
#include <memory>
#include <string>
#include <string_view>

#include "core/error_terms.hpp"
#include "solver/signals.hpp"

namespace calstand::solver {

/// A user's term `NAME=SENSOR:EXPRESSION` (error-model.md, "Custom terms"): parameters
/// NAME.x .y .z, contributing c_i * EXPRESSION to axis i of SENSOR, `{axis}` in the expression
/// replaced by x, y or z for each axis.
///
/// `NAME=SENSOR.AXES:EXPRESSION` (e.g. `k=gyro.z:force_z^2`, `k=accel.xy:rate_{axis}`) acts on
/// the listed axes only, with parameters NAME.<axis> for those: an effect one channel has
/// costs one parameter, not three (the expression language cannot select an axis).
struct CustomTermSpec {
  std::string name;
  core::TermSensor sensor = core::TermSensor::kGyro;
  std::string expression;
  std::array<bool, 3> axes{true, true, true};  ///< x, y, z: the axes the term acts on
  std::string text() const;                    ///< back to NAME=SENSOR[.AXES]:EXPRESSION
};

/// Parses `NAME=SENSOR[.AXES]:EXPRESSION` and compiles the expression once per axis to check it
/// (unknown signals and syntax errors name the position). Throws core::InputError naming `where`
/// (e.g. "--custom grad=gyro:temperature_rat") and why.
CustomTermSpec parse_custom_term(std::string_view text, const std::string& where);

/// Evaluates a custom term's three expressions (muParser) on a sample's signals. Holds the
/// parsers bound to its own variable block: not copyable, not thread safe.
class CustomTermEvaluator {
 public:
  explicit CustomTermEvaluator(const CustomTermSpec& spec);
  ~CustomTermEvaluator();
  CustomTermEvaluator(const CustomTermEvaluator&) = delete;
  CustomTermEvaluator& operator=(const CustomTermEvaluator&) = delete;

  /// The expression per axis (x, y, z) at these signals; 0 on the axes the term does not act on.
  Eigen::Vector3d operator()(const Signals& s);

 private:
  struct Parsers;
  std::array<double, kSignalCount> vars_{};
  std::array<bool, 3> axes_{};
  std::unique_ptr<Parsers> parsers_;
};

}  // namespace calstand::solver
