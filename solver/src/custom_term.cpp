#include "solver/custom_term.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <muParser.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <stdexcept>

#include "core/error.hpp"

namespace calstand::solver {
namespace {

constexpr char kAxisNames[3] = {'x', 'y', 'z'};

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
  std::string selected;
  for (int i = 0; i < 3; ++i) {
    if (axes[static_cast<std::size_t>(i)]) selected += kAxisNames[i];
  }
  return fmt::format("{}={}{}:{}", name, sensor == core::TermSensor::kGyro ? "gyro" : "accel",
                     selected == "xyz" ? "" : "." + selected, expression);
}

CustomTermSpec parse_custom_term(std::string_view text, const std::string& where) {
  const auto eq = text.find('=');
  const auto colon = text.find(':', eq == std::string_view::npos ? 0 : eq);
  if (eq == std::string_view::npos || colon == std::string_view::npos) {
    throw core::InputError(where,
                           "expected NAME=SENSOR:EXPRESSION, e.g. grad=gyro:temperature_rate");
  }
  CustomTermSpec spec;
  spec.name = std::string(text.substr(0, eq));
  std::string_view sensor = text.substr(eq + 1, colon - eq - 1);
  spec.expression = std::string(text.substr(colon + 1));
  if (!is_identifier(spec.name)) {
    throw core::InputError(
        where, fmt::format("term name \"{}\" must be letters, digits and _", spec.name));
  }
  if (core::find_error_term(spec.name)) {
    throw core::InputError(where, fmt::format("\"{}\" is a catalogue term: choose another name "
                                              "for a custom term",
                                              spec.name));
  }
  if (const auto dot = sensor.find('.'); dot != std::string_view::npos) {
    const std::string_view axes = sensor.substr(dot + 1);
    sensor = sensor.substr(0, dot);
    spec.axes = {false, false, false};
    for (char a : axes) {
      const auto* it = std::find(std::begin(kAxisNames), std::end(kAxisNames), a);
      if (it == std::end(kAxisNames) || spec.axes[static_cast<std::size_t>(it - kAxisNames)]) {
        throw core::InputError(where, fmt::format("axes \"{}\" must be some of x, y and z, each "
                                                  "once (e.g. gyro.z, accel.xy)",
                                                  axes));
      }
      spec.axes[static_cast<std::size_t>(it - kAxisNames)] = true;
    }
    if (axes.empty()) {
      throw core::InputError(where, "no axes after the sensor's \".\" (e.g. gyro.z)");
    }
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
  for (int i = 0; i < 3; ++i) {
    if (!spec.axes[static_cast<std::size_t>(i)]) continue;
    const char axis = kAxisNames[i];
    mu::Parser p;
    const std::string expr = expand_axis(spec.expression, axis);
    try {
      bind_signals(p, vars, expr);
      p.Eval();
    } catch (const mu::Parser::exception_type& e) {
      throw core::InputError(where, fmt::format("expression \"{}\": {} (known signals: {})", expr,
                                                e.GetMsg(), fmt::join(signal_names(), ", ")));
    }
  }
  return spec;
}

struct CustomTermEvaluator::Parsers {
  std::array<mu::Parser, 3> axis;
};

CustomTermEvaluator::CustomTermEvaluator(const CustomTermSpec& spec)
    : axes_(spec.axes), parsers_(std::make_unique<Parsers>()) {
  try {
    for (int i = 0; i < 3; ++i) {
      if (axes_[static_cast<std::size_t>(i)]) {
        bind_signals(parsers_->axis[i], vars_, expand_axis(spec.expression, kAxisNames[i]));
      }
    }
  } catch (const mu::Parser::exception_type& e) {
    throw core::InputError("custom term " + spec.text(), e.GetMsg());
  }
}

CustomTermEvaluator::~CustomTermEvaluator() = default;

Eigen::Vector3d CustomTermEvaluator::operator()(const Signals& s) {
  vars_ = signal_values(s);
  try {
    Eigen::Vector3d e = Eigen::Vector3d::Zero();
    for (int i = 0; i < 3; ++i) {
      if (axes_[static_cast<std::size_t>(i)]) e[i] = parsers_->axis[i].Eval();
    }
    return e;
  } catch (const mu::Parser::exception_type& e) {
    // muParser's errors are not std::exceptions; give the caller one it can report.
    throw std::runtime_error("custom term expression \"" + e.GetExpr() + "\": " + e.GetMsg());
  }
}

}  // namespace calstand::solver
