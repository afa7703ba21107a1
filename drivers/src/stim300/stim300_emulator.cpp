// The emulated STIM300 (stim300_emulator.hpp).
#include "drivers/stim300_emulator.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace calstand::drivers::stim300 {
namespace {

std::int32_t stim300_quantise(double value, double counts_per_unit) {
  const double counts = std::round(value * counts_per_unit);
  return static_cast<std::int32_t>(std::clamp(counts, -8388608.0, 8388607.0));
}

void stim300_append(std::vector<std::uint8_t>& out, const std::vector<std::uint8_t>& more) {
  out.insert(out.end(), more.begin(), more.end());
}

}  // namespace

Stim300Emulator::Stim300Emulator(EmulatedUnit unit, Stim300EmulatorSettings settings)
    : unit_(std::move(unit)), settings_(settings) {
  rate_hz_ = settings_.sample_rate_hz;
  if (rate_hz_ <= 0.0) {
    rate_hz_ = unit_.native_rate_hz;  // a rate the unit cannot make: the configurator refuses
    for (double r : sample_rates_hz()) {
      const double ratio = unit_.native_rate_hz / r;
      if (ratio >= 1.0 && std::abs(ratio - std::round(ratio)) < 1e-9) rate_hz_ = r;
    }
  }
  const double ratio = unit_.native_rate_hz / rate_hz_;
  decimation_ = ratio >= 1.0 ? static_cast<std::uint64_t>(std::llround(ratio)) : 1;
}

std::vector<std::uint8_t> Stim300Emulator::startup_datagrams() const {
  std::vector<std::uint8_t> out;
  const bool t = settings_.termination;
  stim300_append(out, encode_digits_datagram(kPartNumber, unit_.model, t));
  stim300_append(out, encode_digits_datagram(kSerialNumber, unit_.serial, t));
  stim300_append(out, encode_configuration(std::array<std::uint8_t, kConfigurationBytes>{}, t));
  return out;
}

std::vector<std::uint8_t> Stim300Emulator::on_host_bytes(std::span<const std::uint8_t> bytes) {
  std::vector<std::uint8_t> out;
  for (std::uint8_t b : bytes) {
    if (b == '\n') continue;
    if (b != '\r') {
      if (line_.size() < 32) line_.push_back(static_cast<char>(b));
      continue;
    }
    const std::string command = line_;
    line_.clear();
    const bool t = settings_.termination;
    if (command == "N") {
      stim300_append(out, encode_digits_datagram(kPartNumber, unit_.model, t));
    } else if (command == "I") {
      stim300_append(out, encode_digits_datagram(kSerialNumber, unit_.serial, t));
    } else if (command == "C") {
      stim300_append(out, encode_configuration(std::array<std::uint8_t, kConfigurationBytes>{}, t));
    } else if (command == "R") {
      samples_ = 0;
      reset_pending_ = true;
      powered_ = true;
      stim300_append(out, startup_datagrams());
    }
    // Anything else (T, SERVICEMODE: calstand sends neither) is not answered.
  }
  return out;
}

std::vector<std::uint8_t> Stim300Emulator::on_sample(const core::ImuSample& sample) {
  std::vector<std::uint8_t> out;
  if (!powered_) {
    powered_ = true;
    out = startup_datagrams();
  }
  if (reset_pending_) {
    reset_pending_ = false;
    counter_base_ = sample.sequence / decimation_;
  }
  if (samples_++ % decimation_ != 0) return out;
  const auto layout = datagram_layout(settings_.datagram_id);
  if (!layout) return out;
  Datagram d;
  d.id = settings_.datagram_id;
  d.counter = static_cast<std::uint8_t>((sample.sequence / decimation_ - counter_base_) & 0xFFu);
  d.latency_us = settings_.latency_us;
  const bool rate = settings_.gyro_output == GyroOutput::kAngularRate;
  const double gyro_counts = gyro_counts_per_unit(settings_.gyro_output);
  const bool accel = settings_.accel_output == AccelOutput::kAcceleration;
  const double per_unit = accel ? 1.0 / kStandardGravity : 1.0 / rate_hz_;
  for (std::size_t a = 0; a < 3; ++a) {
    const auto i = static_cast<Eigen::Index>(a);
    d.value[0][a] =
        stim300_quantise(sample.gyro_dps[i] * (rate ? 1.0 : 1.0 / rate_hz_), gyro_counts);
    d.value[1][a] =
        stim300_quantise(sample.accel_mps2[i] * per_unit,
                         accel_counts_per_unit(settings_.accel_range_g, settings_.accel_output));
    d.value[2][a] = stim300_quantise(sample.accel_mps2[i] * per_unit,
                                     incl_counts_per_unit(settings_.accel_output));
    for (std::size_t g = 0; g < 3; ++g) {
      d.temp[g][a] = static_cast<std::int16_t>(
          std::clamp(std::round(sample.temperature_c * kTempCountsPerDegC), -32768.0, 32767.0));
    }
  }
  stim300_append(out, encode_datagram(d, settings_.termination));
  return out;
}

}  // namespace calstand::drivers::stim300
