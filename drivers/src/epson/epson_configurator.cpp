// The host's configuration dialogue with an Epson IMU over UART (docs/protocols.md, "Epson
// M-G3xx/G5xx", dialogue). Register writes have no reply; each is read back instead.
#include <fmt/format.h>

#include <algorithm>
#include <chrono>

#include "drivers/device_dialogue.hpp"
#include "drivers/epson_wire.hpp"

namespace calstand::drivers::epson {
namespace {

using namespace std::chrono_literals;

constexpr auto kEpsonReplyTimeout = 500ms;
constexpr int kEpsonAttempts = 3;
// Long enough for a burst in flight (36 bytes at 9600 bit/s is 38 ms) to finish after the
// go-to-configuration command before the first register read.
constexpr auto kEpsonSettle = 60ms;
constexpr int kEpsonFilterPolls = 20;

// Four 16-bit registers of ASCII, first character in the low byte (PROD_ID1 "G3" = 0x3347).
std::string epson_ascii(const std::vector<std::uint16_t>& words) {
  std::string out;
  for (std::uint16_t w : words) {
    for (const auto c : {static_cast<char>(w & 0xFFu), static_cast<char>(w >> 8)}) {
      if (c != '\0') out.push_back(c);
    }
  }
  const auto end = out.find_last_not_of(' ');
  return end == std::string::npos ? std::string() : out.substr(0, end + 1);
}

}  // namespace

Configurator::Configurator(const WireFormatSettings& settings)
    : settings_(settings), options_(Options::from_settings(settings, /*require_rate=*/false)) {}

void Configurator::write_byte(ByteTransport& link, std::uint8_t address, std::uint8_t value) {
  const auto command = write_command(address, value);
  const IoResult r = link.write(command, kEpsonReplyTimeout);
  if (!r.ok()) {
    throw DeviceConfigError(
        fmt::format("sending write 0x{:02X} to 0x{:02X}: {}", value, address, r.error));
  }
}

void Configurator::select_window(ByteTransport& link, std::uint8_t window) {
  if (window_ == window) return;
  write_byte(link, kWinCtrlAddress, window);
  window_ = window;
}

std::uint16_t Configurator::read(ByteTransport& link, const Register& reg) {
  select_window(link, reg.window);
  const auto request = read_command(reg.address);
  const auto reply = request_reply(
      link, request,
      [&](std::span<const std::uint8_t> received) -> std::optional<std::vector<std::uint8_t>> {
        if (auto v = find_read_reply(received, reg.address)) {
          return std::vector<std::uint8_t>{static_cast<std::uint8_t>(*v >> 8),
                                           static_cast<std::uint8_t>(*v & 0xFFu)};
        }
        return std::nullopt;
      },
      kEpsonReplyTimeout, kEpsonAttempts, fmt::format("{} read", reg.name));
  return static_cast<std::uint16_t>((reply[0] << 8) | reply[1]);
}

void Configurator::write(ByteTransport& link, const Register& reg, std::uint16_t value) {
  select_window(link, reg.window);
  write_byte(link, reg.address, static_cast<std::uint8_t>(value & 0xFFu));
  write_byte(link, static_cast<std::uint8_t>(reg.address + 1),
             static_cast<std::uint8_t>(value >> 8));
}

void Configurator::write_checked(ByteTransport& link, const Register& reg, std::uint16_t value,
                                 std::uint16_t mask) {
  write(link, reg, value);
  const std::uint16_t got = read(link, reg);
  if ((got & mask) != (value & mask)) {
    throw DeviceConfigError(fmt::format("the device kept {} at 0x{:04X} after 0x{:04X} was written",
                                        reg.name, got, value));
  }
}

void Configurator::enter_configuration(ByteTransport& link) {
  std::uint16_t mode = 0;
  for (int attempt = 0; attempt < kEpsonAttempts; ++attempt) {
    // The window is unknown (a device found streaming); select it and stop sampling.
    window_ = -1;
    select_window(link, kModeCtrl.window);
    write_byte(link, static_cast<std::uint8_t>(kModeCtrl.address + 1), kModeCmdConfig);
    // Drop the tail of a burst that was on its way: a register read is answered only after it.
    (void)read_reply(
        link,
        [](std::span<const std::uint8_t>) { return std::optional<std::vector<std::uint8_t>>(); },
        kEpsonSettle);
    mode = read(link, kModeCtrl);
    if ((mode & kModeStatConfig) != 0) return;
  }
  throw DeviceConfigError(
      fmt::format("the device stays in sampling mode: MODE_CTRL reads 0x{:04X}", mode));
}

UnitIdentity Configurator::configure(ByteTransport& link) {
  if (options_.rate == nullptr) {
    throw DeviceConfigError(
        fmt::format("{:g} Hz is not an output rate of the device (DOUT_RATE: {})",
                    settings_.sample_rate_hz, output_rate_names()));
  }
  enter_configuration(link);

  std::vector<std::uint16_t> words;
  for (std::uint8_t i = 0; i < 4; ++i) {
    words.push_back(
        read(link, {static_cast<std::uint8_t>(kProdId1.address + 2 * i), 1, "PROD_ID"}));
  }
  UnitIdentity id;
  id.model = epson_ascii(words);
  id.firmware = fmt::format("VERSION 0x{:04X}", read(link, kVersion));
  words.clear();
  for (std::uint8_t i = 0; i < 4; ++i) {
    words.push_back(
        read(link, {static_cast<std::uint8_t>(kSerialNum1.address + 2 * i), 1, "SERIAL_NUM"}));
  }
  id.serial = epson_ascii(words);
  if (id.serial.empty()) id.serial = "unknown";

  if (!options_.model.empty() && options_.model != id.model) {
    throw DeviceConfigError(fmt::format("the device's PROD_ID is {}, not the model {} of {}.model",
                                        id.model, options_.model, settings_.where));
  }
  const ModelScale* model = find_model(id.model);
  if (model == nullptr) {
    throw DeviceConfigError(fmt::format(
        "the device's PROD_ID {} has no scale factors here (known: {})", id.model, model_names()));
  }

  // SMPL_CTRL: DOUT_RATE in bits 11:8; FILTER_CTRL: FILTER_SEL in 4:0, then wait while
  // FILTER_STAT (bit 5) says the filter is being set.
  write_checked(link, kSmplCtrl, static_cast<std::uint16_t>(options_.rate->dout_code << 8), 0x0F00);
  write(link, kFilterCtrl, options_.filter_code);
  std::uint16_t filter = kFilterStatBusy;
  for (int i = 0; i < kEpsonFilterPolls && (filter & kFilterStatBusy) != 0; ++i) {
    filter = read(link, kFilterCtrl);
  }
  if ((filter & kFilterStatBusy) != 0 || (filter & 0x1F) != options_.filter_code) {
    throw DeviceConfigError(
        fmt::format("the device kept FILTER_CTRL at 0x{:04X} after 0x{:04X} was written", filter,
                    options_.filter_code));
  }
  write_checked(link, kBurstCtrl1, kBurstCtrl1Value, 0xFFFF);
  write_checked(link, kBurstCtrl2, options_.width_bits == 32 ? kBurstCtrl2Value32 : 0, 0x7000);
  // UART_CTRL low byte: UART_AUTO on, AUTO_START off; the high byte (baud rate) is left alone
  // (writing only the low byte address keeps it).
  write_byte(link, kUartCtrl.address, kUartAuto);
  const std::uint16_t uart = read(link, kUartCtrl);
  if ((uart & 0x03) != kUartAuto) {
    throw DeviceConfigError(fmt::format(
        "the device kept UART_CTRL at 0x{:04X} after 0x{:02X} was written", uart, kUartAuto));
  }

  const std::uint16_t diag = read(link, kDiagStat);
  if (diag != 0) {
    throw DeviceConfigError(fmt::format("DIAG_STAT 0x{:04X}: the device reports an error", diag));
  }
  select_window(link, kModeCtrl.window);
  write_byte(link, static_cast<std::uint8_t>(kModeCtrl.address + 1), kModeCmdSampling);
  return id;
}

}  // namespace calstand::drivers::epson
