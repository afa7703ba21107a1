// The Epson models' scale factors and output rates: data, one row per model, each row citing
// the data sheet it comes from (docs/protocols.md, "Epson M-G3xx/G5xx", scale factors).
#include <fmt/format.h>

#include <array>
#include <cmath>

#include "drivers/epson_protocol.hpp"

namespace calstand::drivers::epson {
namespace {

// Gyro 0.0151515 deg/s/LSB is 1/66 as the sheets print it rounded; 0.00666 is 1/150.
// Temperature: the newer parts read 0.00390625 degC/LSB around 0 LSB = 25 degC; the older
// ones -0.0037918 degC/LSB around 2364 LSB = 25 degC ("T = -0.0037918 x (A - 2364) + 25").
constexpr std::array<ModelScale, 10> kEpsonModels{{
    {"G366PDG0", "M-G366PDG0 Data Sheet, sensor specification", 1.0 / 66, 0.25, 0.00390625, 0},
    {"G330PDG0", "M-G330PDG0 Data Sheet, sensor specification", 1.0 / 66, 0.25, 0.00390625, 0},
    {"G365PDC1", "M-G365PD Data Sheet Rev.20190905, sensor specification (PDC1)", 1.0 / 66, 0.16,
     -0.0037918, 2364},
    {"G365PDF1", "M-G365PD Data Sheet Rev.20190905, sensor specification (PDF1)", 1.0 / 66, 0.4,
     -0.0037918, 2364},
    {"G370PDF1", "M-G370PD Data Sheet, sensor specification (PDF1)", 1.0 / 66, 0.4, -0.0037918,
     2364},
    {"G370PDS0", "M-G370PD Data Sheet, sensor specification (PDS0)", 1.0 / 150, 0.4, -0.0037918,
     2364},
    {"G370PDG0", "M-G370PDG0 Data Sheet, sensor specification", 1.0 / 66, 0.25, 0.00390625, 0},
    {"G370PDT0", "M-G370PDT0 Data Sheet, sensor specification", 1.0 / 150, 0.25, 0.00390625, 0},
    {"G354PDH0", "M-G354PDH0 Data Sheet, sensor specification", 1.0 / 62.5, 0.2, -0.0037918, 2364},
    {"G570PR20", "M-G570PR Data Sheet, sensor specification", 1.0 / 66, 0.5, 0.00390625, 0},
}};

// SMPL_CTRL DOUT_RATE codes and the moving-average TAP count recommended beside each rate
// (M-G365PD Data Sheet, SMPL_CTRL and FILTER_CTRL: "TAP >= N" for each DOUT_RATE).
constexpr std::array<OutputRate, 16> kEpsonRates{{
    {2000.0, 0x00, 0},
    {1000.0, 0x01, 2},
    {500.0, 0x02, 4},
    {250.0, 0x03, 8},
    {125.0, 0x04, 16},
    {62.5, 0x05, 32},
    {31.25, 0x06, 64},
    {15.625, 0x07, 128},
    {400.0, 0x08, 8},
    {200.0, 0x09, 16},
    {100.0, 0x0A, 32},
    {80.0, 0x0B, 32},
    {50.0, 0x0C, 64},
    {40.0, 0x0D, 64},
    {25.0, 0x0E, 128},
    {20.0, 0x0F, 128},
}};

}  // namespace

std::span<const ModelScale> models() { return kEpsonModels; }

const ModelScale* find_model(const std::string& prod_id) {
  for (const auto& m : kEpsonModels) {
    if (prod_id == m.prod_id) return &m;
  }
  return nullptr;
}

std::string model_names() {
  std::string out;
  for (const auto& m : kEpsonModels) out += (out.empty() ? "" : ", ") + std::string(m.prod_id);
  return out;
}

std::span<const OutputRate> output_rates() { return kEpsonRates; }

const OutputRate* find_output_rate(double rate_hz) {
  for (const auto& r : kEpsonRates) {
    if (std::abs(r.rate_hz - rate_hz) < 1e-9) return &r;
  }
  return nullptr;
}

std::string output_rate_names() {
  std::string out;
  for (const auto& r : kEpsonRates)
    out += fmt::format("{}{:g}", out.empty() ? "" : ", ", r.rate_hz);
  return out + " Hz";
}

std::uint8_t moving_average_code(int taps) {
  // FILTER_SEL 0x00 = TAP 0 (none), 0x01 = TAP 2 ... 0x07 = TAP 128 (M-G365PD FILTER_CTRL).
  std::uint8_t code = 0;
  for (int t = 1; t < taps && code < 7; t *= 2) ++code;
  return code;
}

std::optional<std::uint8_t> filter_code(const std::string& name) {
  for (int code = 0; code <= 7; ++code) {
    const int taps = code == 0 ? 0 : 1 << code;
    if (name == fmt::format("moving_average_{}", taps)) return static_cast<std::uint8_t>(code);
  }
  // Kaiser windowed FIR: 0x08.. = TAP 32 fc 50/100/200/400, then TAP 64, then TAP 128.
  constexpr std::array<int, 3> kTaps{32, 64, 128};
  constexpr std::array<int, 4> kCutoffs{50, 100, 200, 400};
  for (std::size_t t = 0; t < kTaps.size(); ++t) {
    for (std::size_t f = 0; f < kCutoffs.size(); ++f) {
      if (name == fmt::format("kaiser_{}_fc{}", kTaps[t], kCutoffs[f])) {
        return static_cast<std::uint8_t>(0x08 + 4 * t + f);
      }
    }
  }
  return std::nullopt;
}

}  // namespace calstand::drivers::epson
