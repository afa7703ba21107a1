#include "suggest_words.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cctype>
#include <cmath>
#include <vector>

#include "core/error_terms.hpp"

namespace calstand::solver::detail {
namespace {

// Significant digits of a searched time constant in the term's text.
constexpr int kTauDigits = 3;

}  // namespace

std::string format_tau(double tau_s) {
  const double scale = std::pow(10.0, std::floor(std::log10(tau_s)) - (kTauDigits - 1));
  return fmt::format("{:g}", std::round(tau_s / scale) * scale);
}

std::string name_of(const std::string& expression, const std::set<std::string>& taken) {
  std::string name;
  for (std::size_t i = 0; i < expression.size(); ++i) {
    const char c = expression[i];
    if (expression.compare(i, 6, "{axis}") == 0) {
      name += "axis";
      i += 5;
    } else if (expression.compare(i, 2, "^2") == 0) {
      name += "_sq";
      ++i;
    } else if (std::isalnum(static_cast<unsigned char>(c)) || c == '_') {
      name += c;
    } else if (c == '.') {
      name += 'p';
    } else if (!name.empty() && name.back() != '_') {
      name += '_';
    }
  }
  while (!name.empty() && name.back() == '_') name.pop_back();
  if (name.empty() || std::isdigit(static_cast<unsigned char>(name[0]))) name = "k_" + name;
  std::string unique = name;
  for (int n = 2; taken.count(unique) || core::find_error_term(unique); ++n) {
    unique = fmt::format("{}_{}", name, n);
  }
  return unique;
}

std::string effect_words(const CustomTermSpec& spec, const FitResult& fit, double tau_s) {
  const bool gyro = spec.sensor == core::TermSensor::kGyro;
  std::vector<std::string> channels, values;
  for (int a = 0; a < 3; ++a) {
    if (!spec.axes[static_cast<std::size_t>(a)]) continue;
    const std::string channel = fmt::format("{}{}", gyro ? 'g' : 'a', "xyz"[a]);
    channels.push_back(channel);
    const std::string parameter = spec.name + "." + "xyz"[a];
    for (const FittedParameter& p : fit.parameters) {
      if (p.name == parameter) {
        values.push_back(fmt::format("{} {:.3g} +- {:.2g}", channel, p.value, p.sigma));
      }
    }
  }
  const std::string unit = gyro ? "deg/s" : "m/s^2";
  const std::string what =
      tau_s > 0.0
          ? fmt::format("a warm-up transient of the {} bias decaying with a {} s time constant",
                        gyro ? "gyro" : "accelerometer", format_tau(tau_s))
      : spec.expression.find("{axis}") != std::string::npos
          ? fmt::format("each {} axis following its own axis's signal",
                        gyro ? "gyro" : "accelerometer")
          : fmt::format("{} following {}", fmt::join(channels, ", "), spec.expression);
  return fmt::format("{}: {} += c * {}, c = {} [{} per unit of the expression]", what,
                     fmt::join(channels, ", "), spec.expression, fmt::join(values, ", "), unit);
}

}  // namespace calstand::solver::detail
