#include "factory/acceptance_names.hpp"

#include <cmath>

#include "core/error_terms.hpp"

namespace calstand::analysis {
namespace {

// The highest polynomial order a temperature term's names are listed to: parse_parameter_name()
// accepts components x1..z9.
constexpr int kMaxPolynomialOrder = 9;

constexpr const char* kAxes[] = {"x", "y", "z"};

}  // namespace

bool glob_match(std::string_view pattern, std::string_view name) {
  // Iterative matching with one backtrack point (the last `*`): linear for the patterns a
  // specification holds, and no recursion on a pattern of many stars.
  std::size_t p = 0, n = 0;
  std::size_t star = std::string_view::npos, resume = 0;
  while (n < name.size()) {
    if (p < pattern.size() && pattern[p] == '*') {
      star = p++;
      resume = n;
    } else if (p < pattern.size() && pattern[p] == name[n]) {
      ++p;
      ++n;
    } else if (star != std::string_view::npos) {
      p = star + 1;
      n = ++resume;
    } else {
      return false;
    }
  }
  while (p < pattern.size() && pattern[p] == '*') ++p;
  return p == pattern.size();
}

const std::vector<NamedQuantity>& catalogue_parameters() {
  static const std::vector<NamedQuantity> kNames = [] {
    std::vector<NamedQuantity> out;
    for (const auto& term : core::error_term_catalogue()) {
      for (const auto& name :
           core::parameter_names(term, term.polynomial_order ? kMaxPolynomialOrder : 1)) {
        out.push_back({name, std::string(term.unit)});
      }
    }
    return out;
  }();
  return kNames;
}

const std::vector<NoiseName>& noise_names() {
  // Short names as datasheets abbreviate them; the bias instability without a suffix is the
  // IEEE 952 coefficient B (the Allan minimum over 0.664), the figure datasheets quote.
  static const std::vector<NoiseName> kNames{
      {"gyro_arw", "angle_random_walk", true, "deg/sqrt(h)", "angle random walk N"},
      {"gyro_bias_instability", "bias_instability_min_coefficient", true, "deg/h",
       "bias instability B = Allan minimum / 0.664"},
      {"gyro_bias_instability_fit", "bias_instability_fit", true, "deg/h",
       "bias instability B as fitted to the Allan curve"},
      {"gyro_allan_min", "bias_instability_min", true, "deg/h", "the Allan deviation's minimum"},
      {"gyro_rrw", "rate_random_walk", true, "deg/h/sqrt(h)", "rate random walk K"},
      {"gyro_rate_ramp", "rate_ramp", true, "deg/h/h", "rate ramp R"},
      {"gyro_quantization", "angle_quantization", true, "arcsec", "angle quantization Q"},
      {"accel_vrw", "velocity_random_walk", false, "m/s/sqrt(h)", "velocity random walk N"},
      {"accel_bias_instability", "bias_instability_min_coefficient", false, "ug",
       "bias instability B = Allan minimum / 0.664"},
      {"accel_bias_instability_fit", "bias_instability_fit", false, "ug",
       "bias instability B as fitted to the Allan curve"},
      {"accel_allan_min", "bias_instability_min", false, "ug", "the Allan deviation's minimum"},
      {"accel_rrw", "acceleration_random_walk", false, "m/s/h/sqrt(h)",
       "acceleration random walk K"},
      {"accel_rate_ramp", "acceleration_ramp", false, "m/s/h/h", "acceleration ramp R"},
      {"accel_quantization", "velocity_quantization", false, "m/s", "velocity quantization Q"},
  };
  return kNames;
}

const std::vector<NamedQuantity>& noise_quantities() {
  static const std::vector<NamedQuantity> kNames = [] {
    std::vector<NamedQuantity> out;
    for (const auto& n : noise_names()) {
      for (const char* axis : kAxes) {
        out.push_back({std::string(n.name) + "." + axis, std::string(n.unit)});
      }
    }
    return out;
  }();
  return kNames;
}

const std::vector<NamedQuantity>& fit_quantities() {
  static const std::vector<NamedQuantity> kNames{{"chi2_dof", ""},
                                                 {"rms_gyro", "deg/s"},
                                                 {"rms_accel", "m/s^2"},
                                                 {"rms_norm", "m/s^2"},
                                                 {"rms_turn", "deg"}};
  return kNames;
}

std::vector<RecordValue> record_parameters(const nlohmann::json& record) {
  std::vector<RecordValue> out;
  for (const auto& p : record.value("parameters", nlohmann::json::array())) {
    RecordValue v;
    v.name = p.value("name", "");
    v.unit = p.value("unit", "");
    v.value = p.value("value", std::nan(""));
    v.sigma = p.value("sigma", std::nan(""));
    out.push_back(std::move(v));
  }
  for (const auto& u : record.value("unidentifiable", nlohmann::json::array())) {
    RecordValue v;
    v.name = u.value("name", "");
    // The record lists no unit for these; the catalogue knows it (custom terms stay without).
    std::string why;
    if (const auto parsed = core::parse_parameter_name(v.name, &why)) {
      v.unit = std::string(parsed->term->unit);
    }
    v.present = false;
    v.note = "not determined by the calibration: " + u.value("reason", std::string("no reason"));
    out.push_back(std::move(v));
  }
  return out;
}

std::vector<RecordValue> record_noise(const nlohmann::json& record) {
  std::vector<RecordValue> out;
  const auto noise = record.find("noise");
  if (noise == record.end() || !noise->is_object() || !noise->contains("channels")) return out;
  const nlohmann::json& channels = (*noise)["channels"];
  for (const auto& n : noise_names()) {
    for (const char* axis : kAxes) {
      const std::string channel = std::string(n.gyro ? "g" : "a") + axis;
      if (!channels.contains(channel)) continue;
      for (const auto& f : channels[channel]) {
        if (f.value("name", "") != n.figure) continue;
        RecordValue v;
        v.name = std::string(n.name) + "." + axis;
        v.unit = f.value("unit", "");
        v.value = f.value("value", std::nan(""));
        if (f.contains("sigma") && f["sigma"].is_number()) v.sigma = f["sigma"].get<double>();
        if (!f.value("resolved", true)) v.note = "not resolved by the noise fit (value 0)";
        out.push_back(std::move(v));
      }
    }
  }
  return out;
}

std::vector<RecordValue> record_fit(const nlohmann::json& record) {
  std::vector<RecordValue> out;
  const auto fit = record.find("fit");
  if (fit == record.end() || !fit->is_object()) return out;
  const auto add = [&](const char* name, const char* unit, const nlohmann::json* value) {
    if (value == nullptr || !value->is_number()) return;
    out.push_back({name, unit, value->get<double>(), std::nullopt, "", true});
  };
  const auto field = [](const nlohmann::json& object, const char* key) -> const nlohmann::json* {
    return object.is_object() && object.contains(key) ? &object[key] : nullptr;
  };
  add("chi2_dof", "", field(*fit, "chi2_dof"));
  if (const nlohmann::json* rms = field(*fit, "residual_rms")) {
    add("rms_gyro", "deg/s", field(*rms, "gyro"));
    add("rms_accel", "m/s^2", field(*rms, "accel"));
  }
  add("rms_norm", "m/s^2", field(*fit, "rms_norm_residual_mps2"));
  add("rms_turn", "deg", field(*fit, "rms_turn_residual_deg"));
  return out;
}

}  // namespace calstand::analysis
