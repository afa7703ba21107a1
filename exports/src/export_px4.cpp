// PX4's thermal compensation and sensor calibration parameters (docs/exports.md, "PX4").
//
// PX4 corrects a sensor sample, in the sensor's own axes and before SENS_BOARD_ROT, as
//   corrected = (raw - TC(T) - CAL_OFF) .* CAL_SCALE          (sensor_calibration library)
//   corrected = (raw - TC(T)) .* TC_SCL                       (the TC_*_SCL_* generation)
//   TC(T) = X0 + X1 d + X2 d^2 + X3 d^3,  d = clip(T, TMIN, TMAX) - TREF
// in rad/s and m/s^2. calstand's record says raw = (I + S + M) truth + b + sum_k c_k dT^k with
// dT = T - T_ref, so with TREF = T_ref the polynomial carries over term by term: X0 = b,
// Xk = c_k, and the diagonal scale inverts as 1 / (1 + 1e-6 s).
#include <fmt/format.h>

#include <algorithm>
#include <cstdint>
#include <string>

#include "export_formats.hpp"
#include "export_terms.hpp"

namespace calstand::analysis::exporting {
namespace {

// MAVLink's MAV_PARAM_TYPE, the last column of a QGroundControl parameter file.
constexpr int kMavParamTypeInt32 = 6;
constexpr int kMavParamTypeReal32 = 9;
// MAVLink component id of the autopilot (MAV_COMP_ID_AUTOPILOT1).
constexpr int kAutopilotComponent = 1;

class ParamsFile {
 public:
  explicit ParamsFile(int sysid) : sysid_(sysid) {}
  void comment(const std::string& line) { text_ += "# " + line + "\n"; }
  void blank_comment() { text_ += "#\n"; }
  void int32(const std::string& name, std::int64_t value) {
    // PX4 keeps device ids (uint32) in INT32 parameters: the same 32 bits, read as signed.
    const auto bits = static_cast<std::int32_t>(static_cast<std::uint32_t>(value));
    line(name, std::to_string(bits), kMavParamTypeInt32);
  }
  void real32(const std::string& name, double value) {
    line(name, float32_text(value), kMavParamTypeReal32);
  }
  const std::string& text() const { return text_; }

 private:
  void line(const std::string& name, const std::string& value, int type) {
    text_ += fmt::format("{}\t{}\t{}\t{}\t{}\n", sysid_, kAutopilotComponent, name, value, type);
  }
  int sysid_;
  std::string text_;
};

struct Px4Sensor {
  const SensorTerms& terms;
  double to_px4_unit;      // from the contract's unit to PX4's (deg/s to rad/s for the gyro)
  const char* tc;          // "G" or "A": TC_G0_..., TC_A0_...
  const char* cal;         // "GYRO" or "ACC": CAL_GYRO0_..., CAL_ACC0_...
  const char* temp_term;   // "gyro_temp_bias"
  std::int64_t device_id;  // PX4's device id, 0 unknown
};

void write_thermal(ParamsFile& f, const Px4Sensor& s, const RecordTerms& t, int i, bool legacy) {
  const std::string p = fmt::format("TC_{}{}_", s.tc, i);
  f.int32(p + "ID", s.device_id);
  f.real32(p + "TREF", t.temperature_ref_c);
  // Without a temperature range the polynomial is zero: clipping T to TREF changes nothing.
  f.real32(p + "TMIN", t.valid_min_c.value_or(t.temperature_ref_c));
  f.real32(p + "TMAX", t.valid_max_c.value_or(t.temperature_ref_c));
  for (int axis = 0; axis < 3; ++axis) {
    f.real32(fmt::format("{}X0_{}", p, axis), s.terms.bias(axis) * s.to_px4_unit);
    for (int k = 1; k <= 3; ++k) {
      const double c = static_cast<std::size_t>(k) <= s.terms.temp_bias.size()
                           ? s.terms.temp_bias[static_cast<std::size_t>(k - 1)](axis)
                           : 0.0;
      f.real32(fmt::format("{}X{}_{}", p, k, axis), c * s.to_px4_unit);
    }
    if (legacy) {
      f.real32(fmt::format("{}SCL_{}", p, axis), 1.0 / (1.0 + 1e-6 * s.terms.scale_ppm(axis)));
    }
  }
}

}  // namespace

ExportResult export_px4(const solver::Calibration& calibration, const ExportOptions& options,
                        bool legacy) {
  const RecordTerms t = record_terms(calibration);
  refuse_temp_order_above(t, 3, legacy ? "px4-legacy (TC_*_X0..X3)" : "px4 (TC_*_X0..X3)");
  const int i = options.instance;
  const Px4Sensor gyro{t.gyro, kRadPerDeg, "G", "GYRO", "gyro_temp_bias", options.px4_gyro_id};
  const Px4Sensor accel{t.accel, 1.0, "A", "ACC", "accel_temp_bias", options.px4_accel_id};

  ExportResult out;
  ParamsFile f(options.mav_sysid);
  f.comment("PX4 parameters from a calstand calibration record (QGroundControl: Parameters,");
  f.comment("Tools, Load from file; then reboot). Conventions: calstand docs/exports.md.");
  f.comment(record_identity(calibration));
  f.comment("Sensor axes (before SENS_BOARD_ROT); offsets in rad/s and m/s^2, subtracted;");
  f.comment("TC polynomial in T - TREF [degC], T clipped to [TMIN, TMAX].");
  if (legacy) {
    f.comment("For PX4 with TC_*_SCL_*: CAL_GYRO*/CAL_ACC* offsets and scales must stay at");
    f.comment("their defaults (0 and 1), PX4 applies them as well.");
  }
  f.blank_comment();
  f.comment("Vehicle-Id Component-Id Name Value Type");
  f.int32("TC_G_ENABLE", 1);
  write_thermal(f, gyro, t, i, legacy);
  f.int32("TC_A_ENABLE", 1);
  write_thermal(f, accel, t, i, legacy);
  if (!legacy) {
    // PX4 subtracts its own CAL offsets after the thermal ones: zero them, or an earlier
    // QGroundControl calibration would be subtracted twice. The accelerometer's scale lives
    // here; PX4 has no gyro scale.
    for (const Px4Sensor* s : {&gyro, &accel}) {
      const std::string p = fmt::format("CAL_{}{}_", s->cal, i);
      f.int32(p + "ID", s->device_id);
      for (const char axis : {'X', 'Y', 'Z'}) f.real32(fmt::format("{}{}OFF", p, axis), 0.0);
    }
    for (int axis = 0; axis < 3; ++axis) {
      f.real32(fmt::format("CAL_ACC{}_{}SCALE", i, static_cast<char>('X' + axis)),
               1.0 / (1.0 + 1e-6 * t.accel.scale_ppm(axis)));
    }
  }
  out.text = f.text();

  for (const Px4Sensor* s : {&gyro, &accel}) {
    if (s->terms.temp_bias.empty()) {
      out.warnings.push_back(fmt::format(
          "the record has no {}: TC_{}{}_X1..X3 are written as 0 and the constant offsets "
          "TC_{}{}_X0_* hold at every temperature",
          s->temp_term, s->tc, i, s->tc, i));
    }
    if (s->device_id == 0) {
      out.warnings.push_back(fmt::format(
          "TC_{0}{1}_ID{2} written as 0: PX4 applies a calibration only to the sensor whose "
          "device id it names; give --px4-{3}-id (PX4's `listener sensor_{3}` shows device_id)",
          s->tc, i, legacy ? "" : fmt::format(" and CAL_{}{}_ID", s->cal, i),
          s == &gyro ? "gyro" : "accel"));
    }
  }
  const auto kept = [legacy](std::string_view term) {
    return term == "gyro_bias" || term == "gyro_temp_bias" || term == "accel_bias" ||
           term == "accel_temp_bias" || term == "accel_scale" || (legacy && term == "gyro_scale");
  };
  if (auto w = left_out_warning(t, kept, legacy ? "PX4 (TC_*_SCL_* generation)" : "PX4")) {
    const bool gyro_scale = std::any_of(t.parameters.begin(), t.parameters.end(),
                                        [](auto& p) { return term_base_name(p) == "gyro_scale"; });
    if (!legacy && gyro_scale) {
      *w += " (the gyro scale has a place only in --format px4-legacy's TC_G*_SCL_*)";
    }
    out.warnings.push_back(*w);
  }
  if (auto w = undetermined_warning(calibration)) out.warnings.push_back(*w);
  return out;
}

}  // namespace calstand::analysis::exporting
