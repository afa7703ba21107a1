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
struct CustomTermSpec {
  std::string name;
  core::TermSensor sensor = core::TermSensor::kGyro;
  std::string expression;
  std::string text() const;  ///< back to NAME=SENSOR:EXPRESSION
};

/// Parses `NAME=SENSOR:EXPRESSION` and compiles the expression once per axis to check it (unknown
/// signals and syntax errors name the position). Throws core::InputError naming `where` (e.g.
/// "--custom grad=gyro:temperature_rat") and why.
CustomTermSpec parse_custom_term(std::string_view text, const std::string& where);

/// Evaluates a custom term's three expressions (muParser) on a sample's signals. Holds the
/// parsers bound to its own variable block: not copyable, not thread safe.
class CustomTermEvaluator {
 public:
  explicit CustomTermEvaluator(const CustomTermSpec& spec);
  ~CustomTermEvaluator();
  CustomTermEvaluator(const CustomTermEvaluator&) = delete;
  CustomTermEvaluator& operator=(const CustomTermEvaluator&) = delete;

  /// The expression per axis (x, y, z) at these signals.
  Eigen::Vector3d operator()(const Signals& s);

 private:
  struct Parsers;
  std::array<double, kSignalCount> vars_{};
  std::unique_ptr<Parsers> parsers_;
};

}  // namespace calstand::solver
