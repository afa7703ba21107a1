// The MTi configuration dialogue (drivers/xsens_configurator.hpp), from MT0101P, "MT Low-Level
// Communication Protocol Documentation": the config/measurement states, the device identity
// messages and SetOutputConfiguration.
#include "drivers/xsens_configurator.hpp"

#include <fmt/format.h>

#include <cmath>

#include "drivers/device_dialogue.hpp"

namespace calstand::drivers::xsens {
namespace {

std::string xsens_trim(const std::vector<std::uint8_t>& text) {
  std::string s(text.begin(), text.end());
  // The product code is padded to its field with spaces or NULs.
  while (!s.empty() && (s.back() == ' ' || s.back() == '\0')) s.pop_back();
  while (!s.empty() && s.front() == ' ') s.erase(s.begin());
  return s;
}

std::string xsens_device_id(const std::vector<std::uint8_t>& data) {
  // DeviceID is a u32 (a u64 on units with the extended identifier); printed in hex, the form
  // on the unit's label.
  std::uint64_t id = 0;
  for (std::uint8_t b : data) id = (id << 8) | b;
  return data.size() > 4 ? fmt::format("{:016X}", id) : fmt::format("{:08X}", id);
}

std::string xsens_firmware(const std::vector<std::uint8_t>& data) {
  // FirmwareRev: major, minor, revision (u8 each), then on newer units build number and SVN
  // revision (u32 each).
  if (data.size() < 3) return {};
  std::string s = fmt::format("{}.{}.{}", data[0], data[1], data[2]);
  if (data.size() >= 11) {
    std::uint32_t build = 0, rev = 0;
    for (int i = 0; i < 4; ++i) build = (build << 8) | data[3 + static_cast<std::size_t>(i)];
    for (int i = 0; i < 4; ++i) rev = (rev << 8) | data[7 + static_cast<std::size_t>(i)];
    s += fmt::format(" build {} rev {}", build, rev);
  }
  return s;
}

}  // namespace

XsensConfigurator::XsensConfigurator(const WireFormatSettings& settings,
                                     std::chrono::milliseconds timeout, int attempts)
    : sample_rate_hz_(settings.sample_rate_hz),
      options_(parse_options(settings)),
      timeout_(timeout),
      attempts_(attempts) {}

Message XsensConfigurator::exchange(ByteTransport& link, std::uint8_t mid,
                                    std::span<const std::uint8_t> data, std::uint8_t reply_mid,
                                    const std::string& what) {
  const auto request = encode_message(mid, data);
  // The reply may come among measurement packets (the unit may be streaming when GoToConfig
  // goes out); an Error message answers a request the device refuses.
  const ReplyFinder finder =
      [reply_mid](
          std::span<const std::uint8_t> received) -> std::optional<std::vector<std::uint8_t>> {
    for (const Message& m : messages_in(received)) {
      if (m.mid == reply_mid || m.mid == mid::kError) {
        return encode_message(m.mid, m.data);
      }
    }
    return std::nullopt;
  };
  const auto reply = request_reply(link, request, finder, timeout_, attempts_, what);
  Message m = scan_message(reply).message;
  if (m.mid == mid::kError) {
    throw DeviceConfigError(fmt::format("{} refused by the device: {}", what, error_text(m.data)));
  }
  return m;
}

UnitIdentity XsensConfigurator::configure(ByteTransport& link) {
  // The output frequency field is a u16 number of Hz (MT0101P, SetOutputConfiguration).
  const double rate = sample_rate_hz_;
  if (!(rate >= 1.0 && rate < 65535.0 && rate == std::floor(rate))) {
    throw DeviceConfigError(fmt::format(
        "an MTi cannot output at {} Hz: SetOutputConfiguration takes a whole number of Hz "
        "(1 to 65534) that the unit's rate divides (2000 Hz on MTi 600-series units)",
        rate));
  }
  exchange(link, mid::kGoToConfig, {}, mid::kGoToConfigAck, "GoToConfig");
  UnitIdentity id;
  id.serial = xsens_device_id(exchange(link, mid::kReqDid, {}, mid::kDeviceId, "ReqDID").data);
  id.model = xsens_trim(
      exchange(link, mid::kReqProductCode, {}, mid::kProductCode, "ReqProductCode").data);
  id.firmware =
      xsens_firmware(exchange(link, mid::kReqFwRev, {}, mid::kFirmwareRev, "ReqFWRev").data);
  const auto wanted = output_configuration(options_, static_cast<std::uint16_t>(rate));
  const auto request = encode_output_configuration(wanted);
  const Message ack = exchange(link, mid::kSetOutputConfiguration, request,
                               mid::kOutputConfiguration, "SetOutputConfiguration");
  // The ack carries the configuration the device applied; a unit may adjust what it cannot
  // make instead of refusing it.
  const auto applied = parse_output_configuration(ack.data);
  if (!applied || *applied != wanted) {
    throw DeviceConfigError(
        "SetOutputConfiguration: the device applied another output configuration than asked "
        "(a rate or data type it cannot make)");
  }
  exchange(link, mid::kGoToMeasurement, {}, mid::kGoToMeasurementAck, "GoToMeasurement");
  if (id.serial.empty()) id.serial = "unknown";
  return id;
}

}  // namespace calstand::drivers::xsens
