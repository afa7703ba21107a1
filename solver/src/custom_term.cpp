#include "solver/custom_term.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <muParser.h>

#include <cctype>
#include <cmath>
#include <stdexcept>

#include "core/error.hpp"

namespace calstand::solver {
namespace {

std::string expand_axis(std::string expr, char axis) {
  const std::string key = "{axis}";
  for (auto pos = expr.find(key); pos != std::string::npos; pos = expr.find(key, pos + 1)) {
    expr.replace(pos, key.size(), std::string(1, axis));
  }
  return expr;
}

bool is_identifier(std::string_view s) {
  if (s.empty() || !(std::isalpha(static_cast<unsigned char>(s[0])) || s[0] == '_')) return false;
  for (char c : s) {
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_')) return false;
  }
  return true;
}

void bind_signals(mu::Parser& p, std::array<double, kSignalCount>& vars, const std::string& expr) {
  for (std::size_t i = 0; i < kSignalCount; ++i) {
    p.DefineVar(std::string(signal_names()[i]), &vars[i]);
  }
  p.SetExpr(expr);
}

}  // namespace

std::string CustomTermSpec::text() const {
  return fmt::format("{}={}:{}", name, sensor == core::TermSensor::kGyro ? "gyro" : "accel",
                     expression);
}

CustomTermSpec parse_custom_term(std::string_view text, const std::string& where) {
  const auto eq = text.find('=');
  const auto colon = text.find(':', eq == std::string_view::npos ? 0 : eq);
  if (eq == std::string_view::npos || colon == std::string_view::npos) {
    throw core::InputError(where, "expected NAME=SENSOR:EXPRESSION, e.g. grad=gyro:temperature_rate");
  }
  CustomTermSpec spec;
  spec.name = std::string(text.substr(0, eq));
  const std::string_view sensor = text.substr(eq + 1, colon - eq - 1);
  spec.expression = std::string(text.substr(colon + 1));
  if (!is_identifier(spec.name)) {
    throw core::InputError(where, fmt::format("term name \"{}\" must be letters, digits and _",
                                              spec.name));
  }
  if (core::find_error_term(spec.name)) {
    throw core::InputError(where, fmt::format("\"{}\" is a catalogue term: choose another name "
                                              "for a custom term",
                                              spec.name));
  }
  if (sensor == "gyro") {
    spec.sensor = core::TermSensor::kGyro;
  } else if (sensor == "accel") {
    spec.sensor = core::TermSensor::kAccel;
  } else {
    throw core::InputError(where, fmt::format("sensor \"{}\" must be gyro or accel", sensor));
  }
  if (spec.expression.empty()) throw core::InputError(where, "the expression is empty");
  // Compile each axis now so that a typo is reported before any data is read.
  std::array<double, kSignalCount> vars{};
  for (char axis : {'x', 'y', 'z'}) {
    mu::Parser p;
    const std::string expr = expand_axis(spec.expression, axis);
    try {
      bind_signals(p, vars, expr);
      p.Eval();
    } catch (const mu::Parser::exception_type& e) {
      throw core::InputError(
          where, fmt::format("expression \"{}\": {} (known signals: {})", expr, e.GetMsg(),
                             fmt::join(signal_names(), ", ")));
    }
  }
  return spec;
}

struct CustomTermEvaluator::Parsers {
  std::array<mu::Parser, 3> axis;
};

CustomTermEvaluator::CustomTermEvaluator(const CustomTermSpec& spec)
    : parsers_(std::make_unique<Parsers>()) {
  const char axes[3] = {'x', 'y', 'z'};
  try {
    for (int i = 0; i < 3; ++i) bind_signals(parsers_->axis[i], vars_, expand_axis(spec.expression, axes[i]));
  } catch (const mu::Parser::exception_type& e) {
    throw core::InputError("custom term " + spec.text(), e.GetMsg());
  }
}

CustomTermEvaluator::~CustomTermEvaluator() = default;

Eigen::Vector3d CustomTermEvaluator::operator()(const Signals& s) {
  vars_ = signal_values(s);
  try {
    return {parsers_->axis[0].Eval(), parsers_->axis[1].Eval(), parsers_->axis[2].Eval()};
  } catch (const mu::Parser::exception_type& e) {
    // muParser's errors are not std::exceptions; give the caller one it can report.
    throw std::runtime_error("custom term expression \"" + e.GetExpr() + "\": " + e.GetMsg());
  }
}

}  // namespace calstand::solver
