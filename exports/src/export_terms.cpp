#include "export_terms.hpp"

#include <fmt/format.h>

#include <cmath>
#include <map>

#include "core/error.hpp"
#include "core/error_terms.hpp"

namespace calstand::analysis::exporting {

Eigen::Matrix3d SensorTerms::scale_matrix() const {
  Eigen::Matrix3d k = Eigen::Matrix3d::Identity() + misalignment;
  for (int i = 0; i < 3; ++i) k(i, i) += 1e-6 * scale_ppm(i);
  return k;
}

Eigen::Vector3d SensorTerms::temp_offset(double dT) const {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  double power = 1.0;
  for (const Eigen::Vector3d& c : temp_bias) {
    power *= dT;
    sum += c * power;
  }
  return sum;
}

std::string term_base_name(const solver::ParameterInfo& parameter) {
  return parameter.term.substr(0, parameter.term.find(':'));
}

RecordTerms record_terms(const solver::Calibration& calibration) {
  RecordTerms t;
  t.temperature_ref_c = calibration.temperature_ref_c;
  if (std::isfinite(calibration.valid_min_c)) t.valid_min_c = calibration.valid_min_c;
  if (std::isfinite(calibration.valid_max_c)) t.valid_max_c = calibration.valid_max_c;
  t.parameters = calibration.model.parameters();
  for (std::size_t i = 0; i < t.parameters.size(); ++i) {
    const double value = calibration.values[static_cast<Eigen::Index>(i)];
    t.values.push_back(value);
    const auto name = core::parse_parameter_name(t.parameters[i].name, nullptr);
    if (!name) continue;  // a custom term's parameter
    const std::string_view term = name->term->name;
    const int a = name->axis;
    const int b = name->second_axis;
    SensorTerms* sensor = term.starts_with("gyro_")    ? &t.gyro
                          : term.starts_with("accel_") ? &t.accel
                                                       : nullptr;
    if (!sensor || a < 0) continue;
    const std::string_view what = term.substr(term.find('_') + 1);
    if (what == "bias") {
      sensor->bias(a) = value;
    } else if (what == "scale") {
      sensor->scale_ppm(a) = value;
    } else if (what == "misalignment" && b >= 0) {
      sensor->misalignment(a, b) = value;
    } else if (what == "temp_bias") {
      if (sensor->temp_bias.size() < static_cast<std::size_t>(name->order)) {
        sensor->temp_bias.resize(static_cast<std::size_t>(name->order), Eigen::Vector3d::Zero());
      }
      sensor->temp_bias[static_cast<std::size_t>(name->order - 1)](a) = value;
    } else if (what == "g_sensitivity" && b >= 0) {
      t.g_sensitivity(a, b) = value;
    }
  }
  return t;
}

std::string join_parameter_names(const std::vector<std::string>& names) {
  // "gyro_misalignment.xy .xz, gyro_scale.x": each term once, then its components.
  std::string out;
  std::string last_term;
  for (const std::string& name : names) {
    const auto dot = name.find('.');
    const std::string term = name.substr(0, dot);
    const std::string component = dot == std::string::npos ? "" : name.substr(dot);
    if (term == last_term) {
      out += " " + component;
    } else {
      out += (out.empty() ? "" : ", ") + name;
      last_term = term;
    }
  }
  return out;
}

std::optional<std::string> left_out_warning(const RecordTerms& terms,
                                            const std::function<bool(std::string_view)>& kept,
                                            std::string_view target) {
  std::vector<std::string> unit_terms;
  std::vector<std::string> station_terms;
  for (const auto& p : terms.parameters) {
    const std::string base = term_base_name(p);
    if (base == "table_tilt") {
      station_terms.push_back(p.name);
    } else if (!kept(base)) {
      unit_terms.push_back(p.name);
    }
  }
  std::string text;
  if (!unit_terms.empty()) {
    text = fmt::format("{} has no parameter for {}: left out of the file", target,
                       join_parameter_names(unit_terms));
  }
  if (!station_terms.empty()) {
    text += fmt::format("{}{} describe the station's table, not the unit: not exported",
                        text.empty() ? "" : "; ", join_parameter_names(station_terms));
  }
  if (text.empty()) return std::nullopt;
  return text;
}

std::optional<std::string> undetermined_warning(const solver::Calibration& calibration) {
  std::vector<std::string> names;
  for (const auto& u : calibration.record.value("unidentifiable", nlohmann::json::array())) {
    names.push_back(u.value("name", std::string("?")));
  }
  if (names.empty()) return std::nullopt;
  return fmt::format("the record did not determine {}: written as 0, as calstand apply uses them",
                     join_parameter_names(names));
}

void refuse_temp_order_above(const RecordTerms& terms, int max_order, std::string_view format) {
  for (const auto* sensor : {&terms.gyro, &terms.accel}) {
    if (sensor->temp_bias.size() <= static_cast<std::size_t>(max_order)) continue;
    const char* term = sensor == &terms.gyro ? "gyro_temp_bias" : "accel_temp_bias";
    throw core::InputError(
        std::string(term) + ":" + std::to_string(sensor->temp_bias.size()),
        fmt::format("a temperature polynomial of order {} cannot be written for {}, whose "
                    "polynomial stops at order {}; calibrate with {}:{} at most",
                    sensor->temp_bias.size(), format, max_order, term, max_order));
  }
}

std::string float32_text(double value) {
  // A negative zero reads as "-0" to a person and as 0 to every loader: write 0.
  return fmt::format("{:.9g}", value == 0.0 ? 0.0 : value);
}

std::string record_identity(const solver::Calibration& calibration) {
  const nlohmann::json& r = calibration.record;
  const nlohmann::json device = r.value("device", nlohmann::json::object());
  const auto text = [](const nlohmann::json& j, const char* key) {
    const std::string v = j.value(key, std::string());
    return v.empty() ? std::string("-") : v;
  };
  std::string runs;
  for (const auto& run : r.value("runs", nlohmann::json::array())) {
    runs += (runs.empty() ? "" : ",") + run.dump();
  }
  return fmt::format("device {} (model {}, serial {}), station {}, runs {}, created {}, {}",
                     text(device, "name"), text(device, "model"), text(device, "serial"),
                     text(r, "station"), runs, text(r, "created_utc"), text(r, "software"));
}

}  // namespace calstand::analysis::exporting
