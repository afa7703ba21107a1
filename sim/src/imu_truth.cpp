#include "sim/imu_truth.hpp"

#include <fmt/format.h>

#include <cmath>
#include <type_traits>

#include "core/error.hpp"
#include "core/error_terms.hpp"
#include "core/schemas.hpp"
#include "core/site.hpp"

namespace calstand::sim {
namespace {

using core::InputError;
using nlohmann::json;

constexpr double kUgToMps2 = 1e-6 * core::kStandardGravity;

// The storage slot of one parameter inside ImuTruth (const or not). A temperature order beyond
// the stored ones is grown when writing and reads as no slot (value 0) when not; nullptr too
// for terms that are not properties of the IMU (earth_rate, table_tilt).
template <typename Truth>
auto slot(Truth& t, const core::ParameterName& p) -> decltype(&t.gyro_bias[0]) {
  const std::string_view term = p.term->name;
  const int i = p.axis;
  const int j = p.second_axis;
  if (term == "gyro_bias") return &t.gyro_bias[i];
  if (term == "gyro_scale") return &t.gyro_scale[i];
  if (term == "gyro_misalignment") return &t.gyro_misalignment(i, j);
  if (term == "gyro_scale_asymmetry") return &t.gyro_scale_asymmetry[i];
  if (term == "gyro_quadratic") return &t.gyro_quadratic[i];
  if (term == "gyro_g_sensitivity") return &t.gyro_g_sensitivity(i, j);
  if (term == "gyro_temp_scale") return &t.gyro_temp_scale[i];
  if (term == "accel_bias") return &t.accel_bias[i];
  if (term == "accel_scale") return &t.accel_scale[i];
  if (term == "accel_misalignment") return &t.accel_misalignment(i, j);
  if (term == "accel_scale_asymmetry") return &t.accel_scale_asymmetry[i];
  if (term == "accel_quadratic") return &t.accel_quadratic[i];
  if (term == "accel_temp_scale") return &t.accel_temp_scale[i];
  if (term == "accel_lever_arm") return &t.accel_lever_arm[i];
  auto poly = [&](auto& coeffs) -> decltype(&t.gyro_bias[0]) {
    const auto order = static_cast<std::size_t>(p.order);
    if (coeffs.size() < order) {
      if constexpr (std::is_const_v<Truth>) {
        return nullptr;
      } else {
        coeffs.resize(order, Eigen::Vector3d::Zero());
      }
    }
    return &coeffs[order - 1][i];
  };
  if (term == "gyro_temp_bias") return poly(t.gyro_temp_bias);
  if (term == "accel_temp_bias") return poly(t.accel_temp_bias);
  return nullptr;
}

core::ParameterName parse_or_throw(const std::string& full_name, const std::string& where) {
  std::string why;
  auto p = core::parse_parameter_name(full_name, &why);
  if (!p) throw InputError(where, why);
  return *p;
}

// A noise field is a number (all three axes) or an array of three.
Eigen::Vector3d triple(const json& obj, const char* key, double scale) {
  if (!obj.contains(key)) return Eigen::Vector3d::Zero();
  const json& v = obj.at(key);
  if (v.is_array()) {
    return Eigen::Vector3d(v[0].get<double>(), v[1].get<double>(), v[2].get<double>()) * scale;
  }
  return Eigen::Vector3d::Constant(v.get<double>() * scale);
}

json triple_json(const Eigen::Vector3d& v, double scale) {
  if (v.x() == v.y() && v.y() == v.z()) return v.x() / scale;
  return json::array({v.x() / scale, v.y() / scale, v.z() / scale});
}

// Datasheet units of the truth file, per noise field: {json key, factor to deg/s or m/s^2}.
struct NoiseUnits {
  const char* white;
  double white_scale;
  const char* bias_instability;
  double bi_scale;
  const char* random_walk;
  double rw_scale;
  const char* gm_sigma;
  double gm_scale;
  const char* turn_on;
  double turn_on_scale;
  const char* quantization;
};

// deg/sqrt(h) -> deg/s/sqrt(Hz) is /60; deg/h -> deg/s is /3600; deg/h/sqrt(h) -> deg/s/sqrt(s)
// is /(3600*60). m/s/sqrt(h) -> m/s^2/sqrt(Hz) is /60; ug/sqrt(h) -> m/s^2/sqrt(s) is ug/60.
const NoiseUnits kGyroUnits{"arw_deg_per_sqrt_h",
                            1.0 / 60.0,
                            "bias_instability_coefficient_deg_per_h",
                            1.0 / 3600.0,
                            "rate_random_walk_deg_per_h_per_sqrt_h",
                            1.0 / (3600.0 * 60.0),
                            "gauss_markov_sigma_deg_per_h",
                            1.0 / 3600.0,
                            "turn_on_bias_deg_per_h",
                            1.0 / 3600.0,
                            "quantization_deg_per_s"};
const NoiseUnits kAccelUnits{"vrw_mps_per_sqrt_h",
                             1.0 / 60.0,
                             "bias_instability_coefficient_ug",
                             kUgToMps2,
                             "random_walk_ug_per_sqrt_h",
                             kUgToMps2 / 60.0,
                             "gauss_markov_sigma_ug",
                             kUgToMps2,
                             "turn_on_bias_ug",
                             kUgToMps2,
                             "quantization_mps2"};

TriadNoise noise_from_json(const json& obj, const NoiseUnits& u) {
  TriadNoise n;
  n.white = triple(obj, u.white, u.white_scale);
  n.bias_instability = triple(obj, u.bias_instability, u.bi_scale);
  n.random_walk = triple(obj, u.random_walk, u.rw_scale);
  n.gauss_markov_sigma = triple(obj, u.gm_sigma, u.gm_scale);
  n.gauss_markov_tau_s = obj.value("gauss_markov_tau_s", 100.0);
  n.turn_on_bias = triple(obj, u.turn_on, u.turn_on_scale);
  n.turn_on_scale_ppm = triple(obj, "turn_on_scale_ppm", 1.0);
  n.quantization = obj.value(u.quantization, 0.0);
  return n;
}

json noise_to_json(const TriadNoise& n, const NoiseUnits& u) {
  json obj = json::object();
  obj[u.white] = triple_json(n.white, u.white_scale);
  obj[u.bias_instability] = triple_json(n.bias_instability, u.bi_scale);
  obj[u.random_walk] = triple_json(n.random_walk, u.rw_scale);
  obj[u.gm_sigma] = triple_json(n.gauss_markov_sigma, u.gm_scale);
  obj["gauss_markov_tau_s"] = n.gauss_markov_tau_s;
  obj[u.turn_on] = triple_json(n.turn_on_bias, u.turn_on_scale);
  obj["turn_on_scale_ppm"] = triple_json(n.turn_on_scale_ppm, 1.0);
  obj[u.quantization] = n.quantization;
  return obj;
}

}  // namespace

void ImuTruth::set_parameter(const std::string& full_name, double value) {
  const auto p = parse_or_throw(full_name, "parameters." + full_name);
  if (p.term->name == "table_tilt") {
    throw InputError("parameters." + full_name,
                     "the table tilt is a property of the station, not of the IMU: it is set in "
                     "the station file (table.tilt_rad)");
  }
  double* s = slot(*this, p);
  if (!s) throw InputError("parameters." + full_name, "not a simulated parameter");
  *s = value;
}

double ImuTruth::parameter(const std::string& full_name) const {
  const auto p = parse_or_throw(full_name, full_name);
  const double* s = slot(*this, p);
  return s ? *s : 0.0;
}

std::vector<std::pair<std::string, double>> ImuTruth::nonzero_parameters() const {
  std::vector<std::pair<std::string, double>> out;
  for (const auto& term : core::error_term_catalogue()) {
    int order = 1;
    if (term.name == "gyro_temp_bias") order = static_cast<int>(gyro_temp_bias.size());
    if (term.name == "accel_temp_bias") order = static_cast<int>(accel_temp_bias.size());
    for (const auto& full_name : core::parameter_names(term, order)) {
      const double v = parameter(full_name);
      if (v != 0.0) out.emplace_back(full_name, v);
    }
  }
  return out;
}

namespace {

// Checks of ImuTruth::validate(): each names the field as the truth file spells it, with the
// value in the file's unit.
class TruthChecker {
 public:
  explicit TruthChecker(const std::string& file) : file_(file) {}

  void finite(const std::string& field, double value) const {
    if (!std::isfinite(value)) fail(field, value, "must be finite");
  }
  void non_negative(const std::string& field, double value) const {
    finite(field, value);
    if (value < 0.0) fail(field, value, "must not be negative");
  }
  void positive(const std::string& field, double value) const {
    finite(field, value);
    if (value <= 0.0) fail(field, value, "must be positive");
  }
  // A per-axis noise figure stored in simulator units; `scale` converts the file's unit to them.
  void non_negative(const std::string& field, const Eigen::Vector3d& v, double scale) const {
    const bool same = v.x() == v.y() && v.y() == v.z();
    for (int i = 0; i < 3; ++i) {
      non_negative(same ? field : fmt::format("{}[{}]", field, i), v[i] / scale);
    }
  }
  [[noreturn]] void fail(const std::string& field, double value, const char* rule) const {
    // 15 digits drop the last-bit noise of the unit conversion (-10.000000000000002 ug).
    throw InputError(fmt::format("{}: {}", file_, field), fmt::format("{:.15g} {}", value, rule));
  }

 private:
  const std::string& file_;
};

void check_noise(const TruthChecker& c, const TriadNoise& n, const NoiseUnits& u,
                 const std::string& sensor) {
  const std::string at = "noise." + sensor + ".";
  c.non_negative(at + u.white, n.white, u.white_scale);
  c.non_negative(at + u.bias_instability, n.bias_instability, u.bi_scale);
  c.non_negative(at + u.random_walk, n.random_walk, u.rw_scale);
  c.non_negative(at + u.gm_sigma, n.gauss_markov_sigma, u.gm_scale);
  c.positive(at + "gauss_markov_tau_s", n.gauss_markov_tau_s);
  c.non_negative(at + u.turn_on, n.turn_on_bias, u.turn_on_scale);
  c.non_negative(at + "turn_on_scale_ppm", n.turn_on_scale_ppm, 1.0);
  c.non_negative(at + u.quantization, n.quantization);
}

}  // namespace

void ImuTruth::validate(const std::string& file_name) const {
  const TruthChecker c(file_name);
  c.finite("temperature_ref_c", temperature_ref_c);
  for (const auto& term : core::error_term_catalogue()) {
    int order = 1;
    if (term.name == "gyro_temp_bias") order = static_cast<int>(gyro_temp_bias.size());
    if (term.name == "accel_temp_bias") order = static_cast<int>(accel_temp_bias.size());
    for (const auto& full_name : core::parameter_names(term, order)) {
      c.finite("parameters." + full_name, parameter(full_name));
    }
  }
  check_noise(c, gyro_noise, kGyroUnits, "gyro");
  check_noise(c, accel_noise, kAccelUnits, "accel");
  c.positive("output.sample_rate_hz", sample_rate_hz);
  c.non_negative("output.gyro_bandwidth_hz", gyro_bandwidth_hz);
  c.non_negative("output.accel_bandwidth_hz", accel_bandwidth_hz);
  if (filter_order < 2 || filter_order > 8 || filter_order % 2 != 0) {
    c.fail("output.filter_order", filter_order, "must be 2, 4, 6 or 8 (an even Butterworth order)");
  }
  if (sequence_modulus < 2) c.fail("output.sequence_modulus", sequence_modulus, "must be >= 2");
  c.non_negative("output.latency_s", latency_s);
  c.finite("output.clock_drift_ppm", clock_drift_ppm);
  c.positive("power_on.time_constant_s", power_on_time_constant_s);
  c.positive("thermal_hysteresis.width_c", hysteresis_width_c);
  for (int i = 0; i < 3; ++i) {
    c.finite("thermal_hysteresis.gyro_bias_deg_per_h", gyro_hysteresis_bias[i]);
    c.finite("thermal_hysteresis.accel_bias_ug", accel_hysteresis_bias[i]);
  }
  for (int i = 0; i < 3; ++i) {
    c.finite("power_on.gyro_bias_deg_per_h", gyro_power_on_bias[i]);
    c.finite("power_on.accel_bias_ug", accel_power_on_bias[i]);
  }
}

ImuTruth imu_truth_from_json(const json& doc, const std::string& file_name) {
  core::validate_or_throw(core::schema("truth.schema.json"), doc, file_name);
  ImuTruth t;
  t.name = doc.value("name", std::string("imu"));
  t.temperature_ref_c = doc.value("temperature_ref_c", 25.0);
  if (doc.contains("parameters")) {
    for (const auto& [name, value] : doc.at("parameters").items()) {
      try {
        t.set_parameter(name, value.get<double>());
      } catch (const InputError& e) {
        throw InputError(file_name, e.what());
      }
    }
  }
  if (doc.contains("noise")) {
    const json& noise = doc.at("noise");
    if (noise.contains("gyro")) t.gyro_noise = noise_from_json(noise.at("gyro"), kGyroUnits);
    if (noise.contains("accel")) t.accel_noise = noise_from_json(noise.at("accel"), kAccelUnits);
  }
  if (doc.contains("output")) {
    const json& o = doc.at("output");
    t.sample_rate_hz = o.value("sample_rate_hz", t.sample_rate_hz);
    t.gyro_bandwidth_hz = o.value("gyro_bandwidth_hz", t.gyro_bandwidth_hz);
    t.accel_bandwidth_hz = o.value("accel_bandwidth_hz", t.accel_bandwidth_hz);
    t.filter_order = o.value("filter_order", t.filter_order);
    t.sequence_modulus = o.value("sequence_modulus", t.sequence_modulus);
    t.latency_s = o.value("latency_s", t.latency_s);
    t.clock_drift_ppm = o.value("clock_drift_ppm", t.clock_drift_ppm);
  }
  if (doc.contains("power_on")) {
    const json& p = doc.at("power_on");
    const auto triple_of = [&](const char* key, double scale) -> Eigen::Vector3d {
      if (!p.contains(key)) return Eigen::Vector3d::Zero();
      const json& a = p.at(key);
      return Eigen::Vector3d(a[0].get<double>(), a[1].get<double>(), a[2].get<double>()) * scale;
    };
    t.gyro_power_on_bias = triple_of("gyro_bias_deg_per_h", 1.0 / 3600.0);
    t.accel_power_on_bias = triple_of("accel_bias_ug", kUgToMps2);
    t.power_on_time_constant_s = p.value("time_constant_s", t.power_on_time_constant_s);
  }
  if (doc.contains("thermal_hysteresis")) {
    const json& h = doc.at("thermal_hysteresis");
    const auto triple_of = [&](const char* key, double scale) -> Eigen::Vector3d {
      if (!h.contains(key)) return Eigen::Vector3d::Zero();
      const json& a = h.at(key);
      return Eigen::Vector3d(a[0].get<double>(), a[1].get<double>(), a[2].get<double>()) * scale;
    };
    t.gyro_hysteresis_bias = triple_of("gyro_bias_deg_per_h", 1.0 / 3600.0);
    t.accel_hysteresis_bias = triple_of("accel_bias_ug", kUgToMps2);
    t.hysteresis_width_c = h.value("width_c", t.hysteresis_width_c);
  }
  t.validate(file_name);
  return t;
}

json imu_truth_to_json(const ImuTruth& t) {
  json params = json::object();
  for (const auto& [name, value] : t.nonzero_parameters()) params[name] = value;
  const auto triple_out = [](const Eigen::Vector3d& v, double scale) {
    return json::array({v.x() / scale, v.y() / scale, v.z() / scale});
  };
  json doc{
      {"format", "calstand-truth/1"},
      {"name", t.name},
      {"temperature_ref_c", t.temperature_ref_c},
      {"parameters", params},
      {"noise",
       {{"gyro", noise_to_json(t.gyro_noise, kGyroUnits)},
        {"accel", noise_to_json(t.accel_noise, kAccelUnits)}}},
      {"output",
       {{"sample_rate_hz", t.sample_rate_hz},
        {"gyro_bandwidth_hz", t.gyro_bandwidth_hz},
        {"accel_bandwidth_hz", t.accel_bandwidth_hz},
        {"filter_order", t.filter_order},
        {"sequence_modulus", t.sequence_modulus},
        {"latency_s", t.latency_s},
        {"clock_drift_ppm", t.clock_drift_ppm}}},
  };
  // Only a unit with a transient says so: truth files of units without one stay as they were.
  if (!t.gyro_power_on_bias.isZero() || !t.accel_power_on_bias.isZero()) {
    doc["power_on"] = {{"gyro_bias_deg_per_h", triple_out(t.gyro_power_on_bias, 1.0 / 3600.0)},
                       {"accel_bias_ug", triple_out(t.accel_power_on_bias, kUgToMps2)},
                       {"time_constant_s", t.power_on_time_constant_s}};
  }
  if (!t.gyro_hysteresis_bias.isZero() || !t.accel_hysteresis_bias.isZero()) {
    doc["thermal_hysteresis"] = {
        {"gyro_bias_deg_per_h", triple_out(t.gyro_hysteresis_bias, 1.0 / 3600.0)},
        {"accel_bias_ug", triple_out(t.accel_hysteresis_bias, kUgToMps2)},
        {"width_c", t.hysteresis_width_c}};
  }
  return doc;
}

std::pair<Eigen::Vector3d, Eigen::Vector3d> deterministic_errors(const ImuTruth& t,
                                                                 const ImuInputs& in) {
  const Eigen::Vector3d& w = in.rate_dps;
  const Eigen::Vector3d& f = in.force_mps2;
  const double dT = in.temperature_c - t.temperature_ref_c;
  const double g0 = core::kStandardGravity;

  Eigen::Vector3d gyro =
      t.gyro_bias + 1e-6 * t.gyro_scale.cwiseProduct(w) + t.gyro_misalignment * w +
      1e-6 * t.gyro_scale_asymmetry.cwiseProduct(w.cwiseAbs()) +
      1e-6 * t.gyro_quadratic.cwiseProduct(w.cwiseAbs2()) + t.gyro_g_sensitivity * (f / g0) +
      1e-6 * dT * t.gyro_temp_scale.cwiseProduct(w);
  double power = 1.0;
  for (const auto& c : t.gyro_temp_bias) {
    power *= dT;
    gyro += c * power;
  }

  const Eigen::Vector3d f_g = f / g0;
  Eigen::Vector3d accel = t.accel_bias + 1e-6 * t.accel_scale.cwiseProduct(f) +
                          t.accel_misalignment * f +
                          1e-6 * t.accel_scale_asymmetry.cwiseProduct(f.cwiseAbs()) +
                          1e-6 * g0 * t.accel_quadratic.cwiseProduct(f_g.cwiseAbs2()) +
                          1e-6 * dT * t.accel_temp_scale.cwiseProduct(f);
  power = 1.0;
  for (const auto& c : t.accel_temp_bias) {
    power *= dT;
    accel += c * power;
  }
  return {gyro, accel};
}

}  // namespace calstand::sim
