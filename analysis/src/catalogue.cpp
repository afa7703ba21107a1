#include "analysis/catalogue.hpp"

#include <array>
#include <stdexcept>
#include <string>

#include "core/error_terms.hpp"
#include "solver/signals.hpp"

namespace calstand::analysis {
namespace {

// Units and meanings as error-model.md gives them; the names are the solver's.
constexpr std::array<CustomSignal, 12> kSignalText = {{
    {"temperature", "degC", "the IMU's temperature"},
    {"temperature_rate", "degC/min", "rate of change of the IMU's temperature"},
    {"elapsed", "s", "time since the run's first sample"},
    {"rate_x", "deg/s", "reference angular rate, body x (table and Earth)"},
    {"rate_y", "deg/s", "reference angular rate, body y (table and Earth)"},
    {"rate_z", "deg/s", "reference angular rate, body z (table and Earth)"},
    {"force_x", "m/s^2", "reference specific force, body x (gravity on a level table)"},
    {"force_y", "m/s^2", "reference specific force, body y (gravity on a level table)"},
    {"force_z", "m/s^2", "reference specific force, body z (gravity on a level table)"},
    {"table_rate_x", "deg/s", "the table's part of the angular rate, body x"},
    {"table_rate_y", "deg/s", "the table's part of the angular rate, body y"},
    {"table_rate_z", "deg/s", "the table's part of the angular rate, body z"},
}};

const char* sensor_name(core::TermSensor s) {
  switch (s) {
    case core::TermSensor::kGyro:
      return "gyro";
    case core::TermSensor::kAccel:
      return "accel";
    case core::TermSensor::kReference:
      break;
  }
  return "both";
}

}  // namespace

std::vector<CustomSignal> custom_signals() {
  std::vector<CustomSignal> out;
  for (const auto name : solver::signal_names()) {
    const CustomSignal* found = nullptr;
    for (const auto& s : kSignalText) {
      if (s.name == name) found = &s;
    }
    if (found == nullptr) {
      throw std::logic_error("custom_signals: signal '" + std::string(name) + "' is not described");
    }
    out.push_back(*found);
  }
  return out;
}

nlohmann::json catalogue_json() {
  nlohmann::json terms = nlohmann::json::array();
  for (const auto& t : core::error_term_catalogue()) {
    terms.push_back({{"name", t.name},
                     {"sensor", sensor_name(t.sensor)},
                     {"unit", t.unit},
                     {"ordered", t.polynomial_order},
                     {"effect", t.effect}});
  }
  nlohmann::json signals = nlohmann::json::array();
  for (const auto& s : custom_signals()) {
    signals.push_back({{"name", s.name}, {"unit", s.unit}, {"meaning", s.meaning}});
  }
  return {{"terms", terms}, {"signals", signals}};
}

}  // namespace calstand::analysis
