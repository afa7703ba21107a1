// The host's configuration dialogue with a VN-100 (drivers/include/drivers/vectornav_device.hpp).
#include <fmt/format.h>

#include <charconv>
#include <optional>

#include "drivers/device_dialogue.hpp"
#include "drivers/vectornav_device.hpp"

namespace calstand::drivers::vectornav {
namespace {

constexpr int kVectornavAttempts = 3;

std::optional<int> vectornav_parse_int(const std::string& text) {
  int value = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc{} || end != text.data() + text.size()) return std::nullopt;
  return value;
}

// The first ASCII message in `received` that answers `command` for `reg` (the register echoed)
// or is an error; the binary stream around it is skipped.
std::optional<AsciiMessage> vectornav_find_reply(std::span<const std::uint8_t> received,
                                                 const std::string& command, int reg,
                                                 std::size_t* end = nullptr) {
  for (std::size_t at = 0; at < received.size(); ++at) {
    if (received[at] != '$') continue;
    AsciiMessage message;
    if (parse_ascii(received.subspan(at), false, message) != Scan::kOk) continue;
    const auto& f = message.fields;
    const bool error = f[0] == "VNERR";
    const bool echo = f[0] == command && f.size() >= 2 && vectornav_parse_int(f[1]) == reg;
    if (error || echo) {
      if (end) *end = at + message.size;
      return message;
    }
  }
  return std::nullopt;
}

}  // namespace

VectornavConfigurator::VectornavConfigurator(Options options, double sample_rate_hz,
                                             std::chrono::milliseconds timeout)
    : options_(options), sample_rate_hz_(sample_rate_hz), timeout_(timeout) {}

std::vector<std::string> VectornavConfigurator::command(ByteTransport& link,
                                                        const std::string& body,
                                                        const std::string& what) {
  const std::string cmd = body.substr(0, body.find(','));
  const auto reg = vectornav_parse_int(body.substr(6, body.find(',', 6) - 6)).value_or(-1);
  const std::string request = ascii_message(body);
  const ReplyFinder finder =
      [&](std::span<const std::uint8_t> received) -> std::optional<std::vector<std::uint8_t>> {
    std::size_t end = 0;
    const auto reply = vectornav_find_reply(received, cmd, reg, &end);
    if (!reply) return std::nullopt;
    return std::vector<std::uint8_t>(
        received.begin() + static_cast<std::ptrdiff_t>(end - reply->size),
        received.begin() + static_cast<std::ptrdiff_t>(end));
  };
  const auto* data = reinterpret_cast<const std::uint8_t*>(request.data());
  const auto bytes =
      request_reply(link, std::span(data, request.size()), finder, timeout_, kVectornavAttempts,
                    fmt::format("{} ({})", what, request.substr(0, request.size() - 2)));
  const auto reply = vectornav_find_reply(bytes, cmd, reg);
  if (!reply) throw DeviceConfigError(fmt::format("vectornav: {}: unreadable reply", what));
  if (reply->fields[0] == "VNERR") {
    throw DeviceConfigError(
        fmt::format("vectornav: {} refused by the device: {}", what,
                    error_text(reply->fields.size() > 1 ? reply->fields[1] : "")));
  }
  return {reply->fields.begin() + 2, reply->fields.end()};
}

UnitIdentity VectornavConfigurator::configure(ByteTransport& link) {
  // Refused before any byte is sent: the unit cannot make a rate its divisor cannot.
  const int divisor = rate_divisor(options_, sample_rate_hz_);
  const auto one = [&](int reg, const std::string& what) {
    const auto values = command(link, fmt::format("VNRRG,{:02d}", reg), what);
    return values.empty() ? std::string() : values[0];
  };
  // The ASCII async output first: its messages would share the line with the binary output.
  command(link, fmt::format("VNWRG,{:02d},0", kRegAsyncDataOutputType),
          "Async Data Output Type (register 6) off");
  UnitIdentity id;
  id.model = one(kRegModelNumber, "Model Number (register 1)");
  const std::string hardware = one(kRegHardwareRevision, "Hardware Revision (register 2)");
  if (!hardware.empty()) id.model += fmt::format(" (hardware revision {})", hardware);
  id.serial = one(kRegSerialNumber, "Serial Number (register 3)");
  id.firmware = one(kRegFirmwareVersion, "Firmware Version (register 4)");
  if (id.serial.empty()) throw DeviceConfigError("vectornav: the Serial Number register is empty");
  command(link, binary_output_body(options_, divisor), "Binary Output Register 1 (register 75)");
  return id;
}

}  // namespace calstand::drivers::vectornav
