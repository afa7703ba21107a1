#include <cmath>
#include <nlohmann/json.hpp>
#include <numbers>

#include "procedures/procedure.hpp"

namespace calstand::procedures {

std::string_view to_string(StepKind kind) {
  switch (kind) {
    case StepKind::kSetTemperature:
      return "set_temperature";
    case StepKind::kMove:
      return "move";
    case StepKind::kRate:
      return "rate";
    case StepKind::kCapture:
      return "capture";
    case StepKind::kWait:
      return "wait";
    case StepKind::kPower:
      return "power";
    case StepKind::kOscillate:
      return "oscillate";
  }
  return "?";
}

double Step::peak_rate_dps() const { return 2.0 * std::numbers::pi * frequency_hz * amplitude_deg; }

double Step::peak_accel_dps2() const {
  const double w = 2.0 * std::numbers::pi * frequency_hz;
  return w * w * amplitude_deg;
}

nlohmann::json Step::to_json() const {
  nlohmann::json j = {{"index", index},
                      {"kind", std::string(to_string(kind))},
                      {"label", label},
                      {"origin", origin_path}};
  if (!loop_values.empty()) {
    nlohmann::json loops = nlohmann::json::object();
    for (const auto& [name, value] : loop_values) loops[name] = value;
    j["loop_values"] = std::move(loops);
  }
  switch (kind) {
    case StepKind::kSetTemperature:
      j["target_c"] = target_c;
      if (ramp_c_per_min) j["ramp_c_per_min"] = *ramp_c_per_min;
      if (wait_for_soak) {
        j["soak"] = {{"tolerance_c", soak.tolerance_c},
                     {"stable_s", soak.stable_s},
                     {"timeout_s", soak.timeout_s}};
      }
      break;
    case StepKind::kMove:
      j["outer_deg"] = outer_deg;
      j["inner_deg"] = inner_deg;
      if (!up.empty()) j["up"] = up;
      if (!imu.empty()) j["imu"] = imu;
      break;
    case StepKind::kRate:
      j["axis"] = axis;
      j["rate_dps"] = rate_dps;
      j["settle_s"] = settle_s;
      j["duration_s"] = duration_s;
      if (revolutions) j["revolutions"] = *revolutions;
      j["rest_after"] = rest_after;
      break;
    case StepKind::kCapture:
    case StepKind::kWait:
      j["duration_s"] = duration_s;
      break;
    case StepKind::kPower:
      j["power"] = power_on ? "on" : "off";
      j["settle_s"] = settle_s;
      if (!imu.empty()) j["imu"] = imu;
      break;
    case StepKind::kOscillate:
      j["axis"] = axis;
      j["amplitude_deg"] = amplitude_deg;
      j["frequency_hz"] = frequency_hz;
      j["cycles"] = cycles;
      j["settle_cycles"] = settle_cycles;
      j["duration_s"] = duration_s;
      break;
  }
  return j;
}

}  // namespace calstand::procedures
