// The STIM300 dialogue: N, I, C while the unit streams (stim300_configurator.hpp).
#include "drivers/stim300_configurator.hpp"

#include <fmt/format.h>

#include <chrono>
#include <string_view>

#include "drivers/device_dialogue.hpp"

namespace calstand::drivers::stim300 {
namespace {

using namespace std::chrono_literals;

constexpr auto kStim300ReplyTimeout = 500ms;
constexpr int kStim300Attempts = 3;

std::vector<std::uint8_t> stim300_ask(ByteTransport& link, const char* command, std::uint8_t id,
                                      const std::string& what) {
  const std::string_view text(command);
  const std::vector<std::uint8_t> request(text.begin(), text.end());
  const ReplyFinder finder =
      [id](std::span<const std::uint8_t> received) -> std::optional<std::vector<std::uint8_t>> {
    const auto scan = find_reply(received, id);
    if (scan.result != ScanResult::kFound) return std::nullopt;
    const auto first = received.begin() + static_cast<std::ptrdiff_t>(scan.offset);
    return std::vector<std::uint8_t>(first, first + static_cast<std::ptrdiff_t>(scan.size));
  };
  return request_reply(link, request, finder, kStim300ReplyTimeout, kStim300Attempts, what);
}

std::string stim300_rates_text() {
  std::string out;
  const auto rates = sample_rates_hz();
  for (std::size_t i = 0; i < rates.size(); ++i) {
    out += fmt::format("{}{:g}", i == 0 ? "" : (i + 1 == rates.size() ? " or " : ", "), rates[i]);
  }
  return out + " Hz";
}

const char* stim300_gyro_text(GyroOutput o) {
  return o == GyroOutput::kAngularRate ? "angular rate" : "incremental angle";
}
const char* stim300_accel_text(AccelOutput o) {
  return o == AccelOutput::kAcceleration ? "acceleration" : "incremental velocity";
}

}  // namespace

Stim300Configurator::Stim300Configurator(WireFormatSettings settings, Stim300Options options)
    : settings_(std::move(settings)), options_(options) {}

UnitIdentity Stim300Configurator::configure(ByteTransport& link) {
  if (!sample_rate_code(settings_.sample_rate_hz)) {
    throw DeviceConfigError(fmt::format("STIM300 samples at {}, not {:g} Hz", stim300_rates_text(),
                                        settings_.sample_rate_hz));
  }
  UnitIdentity identity;
  identity.model = text_of(stim300_ask(link, kCommandPartNumber, kPartNumber, "N (part number)"));
  identity.serial =
      text_of(stim300_ask(link, kCommandSerialNumber, kSerialNumber, "I (serial number)"));
  const auto reply = stim300_ask(link, kCommandConfiguration, kConfiguration, "C (configuration)");
  const auto config = parse_configuration(reply);
  if (!config) {
    throw DeviceConfigError(fmt::format(
        "C (configuration): the reply has {} bytes, not a configuration datagram", reply.size()));
  }
  if (identity.serial.empty()) identity.serial = "(no serial number in its datagram)";
  identity.firmware = fmt::format("firmware revision {}", config->firmware_revision);

  // What the unit says it streams, against the station file.
  const auto rate = sample_rate_from_code(config->sample_rate_code);
  const std::string unit_says = fmt::format(
      "the unit's configuration datagram says: sample rate {}, datagram {}, gyro output {}, "
      "accelerometer output {}, range {} g, termination {}",
      rate ? fmt::format("{:g} Hz", *rate) : fmt::format("code {}", config->sample_rate_code),
      datagram_name(config->datagram_id), stim300_gyro_text(config->gyro_output),
      stim300_accel_text(config->accel_output), config->accel_range_g,
      config->termination ? "CR LF" : "none");
  std::vector<std::string> differ;
  if (!rate || *rate != settings_.sample_rate_hz) {
    differ.push_back(fmt::format("sample_rate_hz {:g}", settings_.sample_rate_hz));
  }
  if (!datagram_layout(config->datagram_id)) {
    differ.push_back("a datagram this driver reads (0x90..0x94, 0xA5..0xA7)");
  } else if (options_.datagram && *options_.datagram != config->datagram_id) {
    differ.push_back(fmt::format("datagram {}", datagram_name(*options_.datagram)));
  }
  if (options_.gyro_output != config->gyro_output) {
    differ.push_back(fmt::format("gyro_output {}", stim300_gyro_text(options_.gyro_output)));
  }
  if (options_.accel_output != config->accel_output) {
    differ.push_back(fmt::format("accel_output {}", stim300_accel_text(options_.accel_output)));
  }
  if (config->accel_range_g != 0 && config->accel_range_g != options_.accel_range_g) {
    differ.push_back(fmt::format("accel_range_g {}", options_.accel_range_g));
  }
  if (options_.termination && *options_.termination != config->termination) {
    differ.push_back(fmt::format("termination {}", *options_.termination));
  }
  if (!differ.empty()) {
    std::string asks;
    for (const auto& d : differ) asks += (asks.empty() ? "" : ", ") + d;
    throw DeviceConfigError(fmt::format(
        "STIM300 {} (serial {}): {}; the station file ({}) asks {} (set the unit in its service "
        "mode)",
        identity.model, identity.serial, unit_says, settings_.where, asks));
  }
  return identity;
}

}  // namespace calstand::drivers::stim300
