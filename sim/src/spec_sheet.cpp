#include "sim/spec_sheet.hpp"

#include <fmt/format.h>

#include <cmath>

#include "core/error.hpp"
#include "core/json_schema.hpp"
#include "core/schemas.hpp"
#include "core/site.hpp"
#include "core/units.hpp"
#include "sim/noise.hpp"

namespace calstand::sim {
namespace {

using nlohmann::json;

std::string_view trimmed(std::string_view s) {
  const auto first = s.find_first_not_of(" \t");
  if (first == std::string_view::npos) return {};
  return s.substr(first, s.find_last_not_of(" \t") - first + 1);
}

// What a figure may be. Every figure of a sheet is a 1-sigma spread or a physical size, so
// none is negative; rates and correlation times must also be non-zero.
enum class Sign { kNonNegative, kPositive };

// Reads one figure of the sheet in `target_unit`, or 0 when absent. Errors name the file and
// the sheet's field with the value as written, e.g. `gyro.random_walk: -0.07 deg/sqrt(h) must
// not be negative`.
class SheetReader {
 public:
  SheetReader(const json& section, std::string file, std::string path)
      : section_(section), file_(std::move(file)), path_(std::move(path)) {}

  double get(const char* key, std::string_view target_unit, Sign sign = Sign::kNonNegative) const {
    if (!section_.contains(key)) return 0.0;
    return convert_field(section_.at(key), fmt::format("{}.{}", path_, key), target_unit, sign);
  }
  bool has(const char* key) const { return section_.contains(key); }
  const json& at(const char* key) const { return section_.at(key); }

  double convert_field(const json& field, const std::string& where, std::string_view target_unit,
                       Sign sign = Sign::kNonNegative) const {
    const std::string text = field.get<std::string>();
    double value = 0.0;
    try {
      const core::Quantity q = core::parse_quantity(text);
      value = core::convert(q.value, q.unit, core::parse_unit(target_unit));
    } catch (const core::InputError& e) {
      throw core::InputError(fmt::format("{}: {}", file_, where), e.what());
    }
    const char* broken = nullptr;
    if (!std::isfinite(value)) {
      broken = "must be finite";
    } else if (value < 0.0) {
      broken = "must not be negative";
    } else if (sign == Sign::kPositive && value == 0.0) {
      broken = "must be positive";
    }
    if (broken) {
      throw core::InputError(fmt::format("{}: {}", file_, where),
                             fmt::format("{} {}", trimmed(text), broken));
    }
    return value;
  }
  const std::string& file() const { return file_; }
  const std::string& path() const { return path_; }

 private:
  const json& section_;
  std::string file_;
  std::string path_;
};

Eigen::Vector3d draw3(NormalSource& n, double sigma) {
  const double x = n.next(), y = n.next(), z = n.next();
  return Eigen::Vector3d(x, y, z) * sigma;
}

Eigen::Matrix3d draw_off_diagonal(NormalSource& n, double sigma) {
  Eigen::Matrix3d m = Eigen::Matrix3d::Zero();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      if (i != j) m(i, j) = n.next() * sigma;
    }
  }
  return m;
}

Eigen::Matrix3d draw_full(NormalSource& n, double sigma) {
  Eigen::Matrix3d m;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) m(i, j) = n.next() * sigma;
  }
  return m;
}

// Noise figures common to both sensors; `rate` is "deg/s" or "m/s^2".
void read_noise(const SheetReader& r, std::string_view rate, std::string_view white_density,
                const char* rate_walk_key, TriadNoise& noise) {
  // Angle/velocity random walk and noise density are the same quantity in different units.
  double white = r.get("white_noise", white_density);
  if (r.has("random_walk")) white = r.get("random_walk", white_density);
  noise.white.setConstant(white);
  // Datasheets quote the Allan deviation floor; the simulator holds the flicker coefficient.
  noise.bias_instability.setConstant(r.get("in_run_bias_stability", rate) /
                                     kFlickerAllanFloorPerCoefficient);
  noise.random_walk.setConstant(r.get(rate_walk_key, fmt::format("{}/sqrt(s)", rate)));
  if (r.has("bias_variation")) {
    const json& bv = r.at("bias_variation");
    noise.gauss_markov_sigma.setConstant(
        r.convert_field(bv.at("sigma"), r.path() + ".bias_variation.sigma", rate));
    noise.gauss_markov_tau_s =
        r.convert_field(bv.at("correlation_time"), r.path() + ".bias_variation.correlation_time",
                        "s", Sign::kPositive);
  }
  noise.turn_on_bias.setConstant(r.get("bias_repeatability", rate));
  noise.turn_on_scale_ppm.setConstant(r.get("scale_factor_repeatability", "ppm"));
  noise.quantization = r.get("quantization", rate);
}

// Where one sensor's drawn errors go in ImuTruth.
struct SensorTerms {
  Eigen::Vector3d& bias;
  Eigen::Vector3d& scale;
  Eigen::Matrix3d& misalignment;
  Eigen::Vector3d& scale_asymmetry;
  std::vector<Eigen::Vector3d>& temp_bias;
  Eigen::Vector3d& temp_scale;
  TriadNoise& noise;
};

// The figures gyro and accelerometer sheets share; `rate` is the sensor's output unit
// ("deg/s" or "m/s^2"), ratios are read in ppm.
void draw_sensor(const SheetReader& r, std::string_view rate, const char* rate_walk_key,
                 NormalSource& draw, SensorTerms out) {
  read_noise(r, rate, fmt::format("{}/sqrt(Hz)", rate), rate_walk_key, out.noise);
  // Without an initial-bias figure, the turn-on spread is the best guess of the fixed bias.
  const double bias_sigma = r.has("bias") ? r.get("bias", rate) : r.get("bias_repeatability", rate);
  out.bias = draw3(draw, bias_sigma);
  const double scale_sigma = r.has("scale_factor_error") ? r.get("scale_factor_error", "ppm")
                                                         : r.get("scale_factor_stability", "ppm");
  out.scale = draw3(draw, scale_sigma);
  out.misalignment = draw_off_diagonal(draw, r.get("nonorthogonality", "rad"));
  out.scale_asymmetry = draw3(draw, r.get("scale_factor_asymmetry", "ppm"));
  const double temp_coefficient = r.get("bias_temperature_coefficient_per_degc", rate);
  if (temp_coefficient > 0.0) out.temp_bias = {draw3(draw, temp_coefficient)};
  out.temp_scale = draw3(draw, r.get("scale_temperature_coefficient_per_degc", "ppm"));
}

}  // namespace

ImuTruth truth_from_spec(const json& spec, const std::string& file_name, std::uint64_t seed) {
  core::validate_or_throw(core::schema("spec-sheet.schema.json"), spec, file_name);
  ImuTruth t;
  t.name = spec.at("name").get<std::string>();
  NormalSource draw(derive_seed(seed, "spec-sheet-draw", 0));

  const SheetReader gyro(spec.at("gyro"), file_name, "gyro");
  const SheetReader accel(spec.at("accel"), file_name, "accel");

  draw_sensor(gyro, "deg/s", "rate_random_walk", draw,
              {t.gyro_bias, t.gyro_scale, t.gyro_misalignment, t.gyro_scale_asymmetry,
               t.gyro_temp_bias, t.gyro_temp_scale, t.gyro_noise});
  // g-sensitivity in (deg/s)/g: converting "deg/s/g" to "deg/s/g" checks the dimension.
  t.gyro_g_sensitivity = draw_full(draw, gyro.get("g_sensitivity", "deg/s/g"));

  draw_sensor(accel, "m/s^2", "acceleration_random_walk", draw,
              {t.accel_bias, t.accel_scale, t.accel_misalignment, t.accel_scale_asymmetry,
               t.accel_temp_bias, t.accel_temp_scale, t.accel_noise});
  // Vibration (second-order) sensitivity, ug/g^2 as the contract's accel_quadratic.
  t.accel_quadratic = draw3(draw, accel.get("vibration_sensitivity", "ug/g^2"));

  // Output: one sample rate for both sensors.
  if (spec.contains("output")) {
    const SheetReader out(spec.at("output"), file_name, "output");
    if (out.has("sample_rate")) t.sample_rate_hz = out.get("sample_rate", "Hz", Sign::kPositive);
    if (out.has("latency")) t.latency_s = out.get("latency", "s");
    t.filter_order = spec.at("output").value("filter_order", t.filter_order);
  }
  // Each sensor's bandwidth is its own output filter; one at or above Nyquist filters nothing.
  const auto output_filter = [&](const SheetReader& r) {
    const double b = r.get("bandwidth", "Hz");
    return b < t.sample_rate_hz / 2.0 ? b : 0.0;
  };
  t.gyro_bandwidth_hz = output_filter(gyro);
  t.accel_bandwidth_hz = output_filter(accel);
  t.temperature_ref_c = 25.0;
  // The warm-up transient: drawn last, and only for a sheet that states it, so that every
  // other sheet draws the same unit as before the figure existed.
  if (gyro.has("warm_up_bias") || accel.has("warm_up_bias")) {
    if (!spec.contains("output") || !spec.at("output").contains("warm_up_time_constant")) {
      throw core::InputError(file_name,
                             "a warm_up_bias needs output.warm_up_time_constant: how "
                             "fast the power-on transient settles");
    }
    const SheetReader out(spec.at("output"), file_name, "output");
    t.power_on_time_constant_s = out.get("warm_up_time_constant", "s", Sign::kPositive);
    t.gyro_power_on_bias = draw3(draw, gyro.get("warm_up_bias", "deg/s"));
    t.accel_power_on_bias = draw3(draw, accel.get("warm_up_bias", "m/s^2"));
  }
  // Every figure was checked above under its sheet name; this catches what a combination of
  // them could still break, named as the truth file would name it.
  t.validate(file_name);
  return t;
}

std::optional<json> builtin_spec(std::string_view name) {
  const auto text = builtin_file(fmt::format("{}.spec.json", name));
  if (!text) return std::nullopt;
  return core::parse_json_text(*text, fmt::format("<built-in {}.spec.json>", name));
}

std::vector<std::string> builtin_spec_names() {
  std::vector<std::string> names;
  constexpr std::string_view kSuffix = ".spec.json";
  for (const auto f : builtin_file_names()) {
    if (f.size() > kSuffix.size() && f.substr(f.size() - kSuffix.size()) == kSuffix) {
      names.emplace_back(f.substr(0, f.size() - kSuffix.size()));
    }
  }
  return names;
}

}  // namespace calstand::sim
