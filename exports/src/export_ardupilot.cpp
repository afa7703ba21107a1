// ArduPilot's IMU temperature calibration, offsets and scales (docs/exports.md, "ArduPilot").
//
// ArduPilot (AP_InertialSensor_Backend::_rotate_and_correct_accel/_gyro with
// AP_InertialSensor_tempcal.cpp) corrects a sample, after the driver's fixed chip rotation and
// before AHRS_ORIENTATION, as
//   v -= P(clip(T) - 35) - P(clip(T_cal) - 35)      P(x) = 1e-6 (A1 x + A2 x^2 + A3 x^3)
//   v -= OFFS;  accel only: v .*= SCAL
// with T clipped to [TMIN, TMAX], T_cal the INS_ACCn_CALTEMP / INS_GYRn_CALTEMP the offsets
// were measured at, rad/s and m/s^2. calstand's polynomial C(T) = sum_k c_k (T - T_ref)^k is
// re-expanded about ArduPilot's fixed 35 degC (P(T - 35) = C(T) - C(35)); the record's bias
// then needs OFFS = b + C(T_cal), and the constant parts cancel exactly.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "export_formats.hpp"
#include "export_terms.hpp"

namespace calstand::analysis::exporting {
namespace {

// AP_InertialSensor_tempcal.cpp: the polynomial's fixed reference temperature, and the factor
// its parameters are stored with ("so params are easy to work with in GUI parameter editors").
constexpr double kArduPilotTempReferenceC = 35.0;
constexpr double kArduPilotCoefficientScale = 1e6;

double binomial(int n, int k) {
  double b = 1.0;
  for (int j = 1; j <= k; ++j) b = b * (n - k + j) / j;
  return b;
}

// The coefficients A1..A3 (unscaled) of sum_k c_k (x + delta)^k, x = T - 35, without the
// constant: A_j = sum_{k >= j} c_k C(k, j) delta^(k - j), delta = 35 - T_ref.
std::vector<Eigen::Vector3d> reexpand(const SensorTerms& s, double delta) {
  std::vector<Eigen::Vector3d> a(3, Eigen::Vector3d::Zero());
  for (int j = 1; j <= 3; ++j) {
    for (int k = j; k <= static_cast<int>(s.temp_bias.size()); ++k) {
      a[static_cast<std::size_t>(j - 1)] +=
          s.temp_bias[static_cast<std::size_t>(k - 1)] * binomial(k, j) * std::pow(delta, k - j);
    }
  }
  return a;
}

class ParamFile {
 public:
  void comment(const std::string& line) { text_ += "# " + line + "\n"; }
  void value(const std::string& name, double v) { text_ += name + "," + float32_text(v) + "\n"; }
  const std::string& text() const { return text_; }

 private:
  std::string text_;
};

}  // namespace

ExportResult export_ardupilot(const solver::Calibration& calibration,
                              const ExportOptions& options) {
  const RecordTerms t = record_terms(calibration);
  refuse_temp_order_above(t, 3, "ardupilot (INS_TCALn_ACC1..3, GYR1..3)");
  const int n = options.instance + 1;
  // The first IMU's offsets have no number: INS_ACCOFFS_X, then INS_ACC2OFFS_X, INS_ACC3OFFS_X.
  const std::string sfx = n == 1 ? "" : std::to_string(n);
  const bool thermal = !t.gyro.temp_bias.empty() || !t.accel.temp_bias.empty();
  const double tmin = t.valid_min_c.value_or(t.temperature_ref_c);
  const double tmax = t.valid_max_c.value_or(t.temperature_ref_c);
  // The offsets are stated at T_ref, where the record's bias is b; ArduPilot clips the
  // calibration temperature into [TMIN, TMAX] as it does T, so state them there.
  const double tcal = std::clamp(t.temperature_ref_c, std::min(tmin, tmax), std::max(tmin, tmax));
  const double delta = kArduPilotTempReferenceC - t.temperature_ref_c;

  ParamFile f;
  f.comment("ArduPilot parameters from a calstand calibration record (Mission Planner: Config,");
  f.comment("Full Parameter List, Load from file; MAVProxy: param load FILE). Conventions:");
  f.comment("calstand docs/exports.md. " + record_identity(calibration));
  f.comment("Board axes after the driver's chip rotation; rad/s and m/s^2; offsets subtracted,");
  f.comment("then the accel scales multiply. INS_TCAL polynomials in T - 35 degC, times 1e6.");
  f.comment("INS_GYR_CAL=1 (the default) measures the gyro offsets again at every boot.");
  f.value(fmt::format("INS_TCAL{}_ENABLE", n), thermal ? 1.0 : 0.0);
  f.value(fmt::format("INS_TCAL{}_TMIN", n), tmin);
  f.value(fmt::format("INS_TCAL{}_TMAX", n), tmax);
  struct Sensor {
    const SensorTerms& terms;
    double to_unit;
    const char* tcal;  // ACC, GYR in INS_TCALn_ACC1_X
    const char* name;  // ACC, GYR in INS_ACC2OFFS_X, INS_ACC2_CALTEMP
    const char* temp_term;
  };
  const Sensor accel{t.accel, 1.0, "ACC", "ACC", "accel_temp_bias"};
  const Sensor gyro{t.gyro, kRadPerDeg, "GYR", "GYR", "gyro_temp_bias"};
  for (const Sensor* s : {&accel, &gyro}) {
    const std::vector<Eigen::Vector3d> a = reexpand(s->terms, delta);
    for (int k = 1; k <= 3; ++k) {
      for (int axis = 0; axis < 3; ++axis) {
        f.value(fmt::format("INS_TCAL{}_{}{}_{}", n, s->tcal, k, static_cast<char>('X' + axis)),
                a[static_cast<std::size_t>(k - 1)](axis) * s->to_unit * kArduPilotCoefficientScale);
      }
    }
  }
  for (const Sensor* s : {&accel, &gyro}) {
    f.value(fmt::format("INS_{}{}_CALTEMP", s->name, n), tcal);
    const Eigen::Vector3d offset =
        (s->terms.bias + s->terms.temp_offset(tcal - t.temperature_ref_c)) * s->to_unit;
    for (int axis = 0; axis < 3; ++axis) {
      f.value(fmt::format("INS_{}{}OFFS_{}", s->name, sfx, static_cast<char>('X' + axis)),
              offset(axis));
    }
  }
  for (int axis = 0; axis < 3; ++axis) {
    f.value(fmt::format("INS_ACC{}SCAL_{}", sfx, static_cast<char>('X' + axis)),
            1.0 / (1.0 + 1e-6 * t.accel.scale_ppm(axis)));
  }

  ExportResult out;
  out.text = f.text();
  for (const Sensor* s : {&accel, &gyro}) {
    if (s->terms.temp_bias.empty()) {
      out.warnings.push_back(fmt::format(
          "the record has no {}: INS_TCAL{}_{}1..3 are written as 0 and the offsets "
          "hold at every temperature{}",
          s->temp_term, n, s->tcal, thermal ? "" : fmt::format(" (INS_TCAL{}_ENABLE = 0)", n)));
    }
  }
  const auto kept = [](std::string_view term) {
    return term == "gyro_bias" || term == "gyro_temp_bias" || term == "accel_bias" ||
           term == "accel_temp_bias" || term == "accel_scale";
  };
  if (auto w = left_out_warning(t, kept, "ArduPilot")) out.warnings.push_back(*w);
  if (auto w = undetermined_warning(calibration)) out.warnings.push_back(*w);
  return out;
}

}  // namespace calstand::analysis::exporting
