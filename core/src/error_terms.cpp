#include "core/error_terms.hpp"

#include <fmt/format.h>

#include <charconv>

namespace calstand::core {
namespace {

const std::vector<std::string_view> kXyz{"x", "y", "z"};
const std::vector<std::string_view> kOffDiagonal{"xy", "xz", "yx", "yz", "zx", "zy"};
const std::vector<std::string_view> kFull3x3{"xx", "xy", "xz", "yx", "yy", "yz", "zx", "zy", "zz"};

int axis_index(char c) {
  switch (c) {
    case 'x':
      return 0;
    case 'y':
      return 1;
    case 'z':
      return 2;
    default:
      return -1;
  }
}

}  // namespace

const std::vector<ErrorTermInfo>& error_term_catalogue() {
  static const std::vector<ErrorTermInfo> kTerms{
      {"gyro_bias", TermSensor::kGyro, kXyz, "deg/s", "constant rate offset of each gyro", false},
      {"gyro_scale", TermSensor::kGyro, kXyz, "ppm",
       "scale-factor error: output grows in proportion to the input rate", false},
      {"gyro_misalignment", TermSensor::kGyro, kOffDiagonal, "rad",
       "sensing axes not orthogonal to the body frame: rate about one axis leaks into another",
       false},
      {"gyro_scale_asymmetry", TermSensor::kGyro, kXyz, "ppm",
       "scale factor differs between clockwise and counter-clockwise rotation", false},
      {"gyro_quadratic", TermSensor::kGyro, kXyz, "ppm/(deg/s)",
       "scale-factor nonlinearity growing with the square of the rate", false},
      {"gyro_g_sensitivity", TermSensor::kGyro, kFull3x3, "(deg/s)/g",
       "gyro bias that depends on the specific force (orientation in gravity)", false},
      {"gyro_temp_bias",
       TermSensor::kGyro,
       {},
       "deg/s/degC^k",
       "gyro bias drifting with temperature (polynomial in T - Tref)",
       true},
      {"gyro_temp_scale", TermSensor::kGyro, kXyz, "ppm/degC",
       "gyro scale factor drifting with temperature", false},
      {"earth_rate",
       TermSensor::kReference,
       {},
       "-",
       "the Earth's rotation seen by the gyros, added to the table rate",
       false},
      {"accel_bias", TermSensor::kAccel, kXyz, "m/s^2", "constant offset of each accelerometer",
       false},
      {"accel_scale", TermSensor::kAccel, kXyz, "ppm",
       "scale-factor error: output grows in proportion to the specific force", false},
      {"accel_misalignment", TermSensor::kAccel, kOffDiagonal, "rad",
       "sensing axes not orthogonal to the body frame: force along one axis leaks into another",
       false},
      {"accel_scale_asymmetry", TermSensor::kAccel, kXyz, "ppm",
       "scale factor differs between +g and -g along an axis", false},
      {"accel_quadratic", TermSensor::kAccel, kXyz, "ug/g^2",
       "nonlinearity (vibration rectification) growing with the square of the force", false},
      {"accel_temp_bias",
       TermSensor::kAccel,
       {},
       "m/s^2/degC^k",
       "accelerometer bias drifting with temperature (polynomial in T - Tref)",
       true},
      {"accel_temp_scale", TermSensor::kAccel, kXyz, "ppm/degC",
       "accelerometer scale factor drifting with temperature", false},
      {"accel_lever_arm", TermSensor::kAccel, kXyz, "m",
       "accelerometers off the rotation centre feel centripetal and tangential acceleration",
       false},
      {"table_tilt",
       TermSensor::kReference,
       {"east", "north"},
       "rad",
       "the table base is not level: gravity is tilted in the body frame",
       false},
  };
  return kTerms;
}

const ErrorTermInfo* find_error_term(std::string_view name) {
  for (const auto& t : error_term_catalogue()) {
    if (t.name == name) return &t;
  }
  return nullptr;
}

std::optional<ParameterName> parse_parameter_name(std::string_view full_name, std::string* why) {
  auto fail = [&](std::string text) -> std::optional<ParameterName> {
    if (why) *why = std::move(text);
    return std::nullopt;
  };
  const auto dot = full_name.find('.');
  if (dot == std::string_view::npos) {
    return fail(fmt::format("\"{}\" is not <term>.<component>", full_name));
  }
  const std::string_view term_name = full_name.substr(0, dot);
  const std::string_view component = full_name.substr(dot + 1);
  const ErrorTermInfo* term = find_error_term(term_name);
  if (!term) return fail(fmt::format("unknown error term \"{}\"", term_name));

  ParameterName p;
  p.term = term;
  p.component = std::string(component);
  if (term->polynomial_order) {
    // x1, y1, z1, x2, ...: axis letter then the power of dT.
    int order = 0;
    const bool ok =
        component.size() >= 2 && axis_index(component[0]) >= 0 &&
        std::from_chars(component.data() + 1, component.data() + component.size(), order).ec ==
            std::errc{} &&
        order >= 1 && order <= 9 && std::to_string(order) == component.substr(1);
    if (!ok) {
      return fail(
          fmt::format("unknown component \"{}\" of {} (expected x1..z9)", component, term_name));
    }
    p.axis = axis_index(component[0]);
    p.order = order;
    return p;
  }
  for (const auto& c : term->components) {
    if (c != component) continue;
    if (c.size() >= 1) p.axis = axis_index(c[0]);
    if (c.size() == 2) p.second_axis = axis_index(c[1]);
    return p;
  }
  std::string list;
  for (const auto& c : term->components) list += (list.empty() ? "" : " ") + std::string(c);
  if (term->components.empty()) {
    return fail(fmt::format("{} has no parameters", term_name));
  }
  return fail(fmt::format("unknown component \"{}\" of {} (expected one of: {})", component,
                          term_name, list));
}

std::vector<std::string> parameter_names(const ErrorTermInfo& term, int order) {
  std::vector<std::string> names;
  if (term.polynomial_order) {
    for (int k = 1; k <= order; ++k) {
      for (const auto& a : kXyz) names.push_back(fmt::format("{}.{}{}", term.name, a, k));
    }
    return names;
  }
  for (const auto& c : term.components) names.push_back(fmt::format("{}.{}", term.name, c));
  return names;
}

}  // namespace calstand::core
