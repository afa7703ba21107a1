// A VN-100 on the line for sim-station and tests (drivers/include/drivers/vectornav_device.hpp).
#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <optional>

#include "drivers/vectornav_device.hpp"

namespace calstand::drivers::vectornav {
namespace {

// Error codes the emulator answers with [UM004 §4.5 table 20].
constexpr int kVectornavErrInvalidChecksum = 3;
/// The VN-100's IMU rate, which the RateDivisor divides [Hz] [UM001 p. 35].
constexpr double kVectornavEmuImuRateHz = 800.0;
constexpr int kVectornavErrInvalidCommand = 4;
constexpr int kVectornavErrNotEnoughParameters = 5;
constexpr int kVectornavErrTooManyParameters = 6;
constexpr int kVectornavErrInvalidParameter = 7;
constexpr int kVectornavErrInvalidRegister = 8;

std::optional<long> vectornav_emu_number(const std::string& text, int base) {
  long value = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value, base);
  if (text.empty() || ec != std::errc{} || end != text.data() + text.size()) return std::nullopt;
  return value;
}

std::string vectornav_emu_error(int code) {
  return ascii_message(fmt::format("VNERR,{:02d}", code));
}

}  // namespace

VectornavEmulator::VectornavEmulator(EmulatedUnit unit, std::string hardware_revision)
    : unit_(std::move(unit)), hardware_revision_(std::move(hardware_revision)) {}

std::string VectornavEmulator::binary_output_fields() const {
  std::string out = fmt::format("{},{},{:02X}", async_mode_, divisor_,
                                (common_ ? kGroupCommon : 0) | (imu_ ? kGroupImu : 0));
  if (common_) out += fmt::format(",{:04X}", common_);
  if (imu_) out += fmt::format(",{:04X}", imu_);
  return out;
}

std::string VectornavEmulator::answer(const AsciiMessage& message) {
  const auto& f = message.fields;
  const bool read = f[0] == "VNRRG";
  if (!read && f[0] != "VNWRG") return vectornav_emu_error(kVectornavErrInvalidCommand);
  if (f.size() < 2) return vectornav_emu_error(kVectornavErrNotEnoughParameters);
  const auto reg = vectornav_emu_number(f[1], 10);
  if (!reg) return vectornav_emu_error(kVectornavErrInvalidParameter);
  // Replies echo the register as the host wrote it [UM001 §5.1.1: "$VNRRG,5,9600*65"].
  const std::string head = f[0] + "," + f[1];
  if (read) {
    if (f.size() > 2) return vectornav_emu_error(kVectornavErrTooManyParameters);
    switch (*reg) {
      case kRegModelNumber:
        return ascii_message(head + "," + unit_.model);
      case kRegHardwareRevision:
        return ascii_message(head + "," + hardware_revision_);
      case kRegSerialNumber:
        return ascii_message(head + "," + unit_.serial);
      case kRegFirmwareVersion:
        return ascii_message(head + "," + unit_.firmware);
      case kRegAsyncDataOutputType:
        return ascii_message(fmt::format("{},{}", head, ador_));
      case kRegBinaryOutput1:
        return ascii_message(head + "," + binary_output_fields());
      default:
        return vectornav_emu_error(kVectornavErrInvalidRegister);
    }
  }
  if (*reg >= kRegModelNumber && *reg <= kRegFirmwareVersion) {
    return ascii_message("VNERR,09");  // read-only registers: Unauthorized Access
  }
  if (*reg == kRegAsyncDataOutputType) {
    // ADOR [, serial port] [UM004 §5.7].
    if (f.size() < 3) return vectornav_emu_error(kVectornavErrNotEnoughParameters);
    if (f.size() > 4) return vectornav_emu_error(kVectornavErrTooManyParameters);
    const auto ador = vectornav_emu_number(f[2], 10);
    if (!ador || *ador < 0) return vectornav_emu_error(kVectornavErrInvalidParameter);
    ador_ = static_cast<int>(*ador);
  } else if (*reg == kRegBinaryOutput1) {
    // AsyncMode, RateDivisor, OutputGroup (hex), one field word (hex) per group.
    if (f.size() < 6) return vectornav_emu_error(kVectornavErrNotEnoughParameters);
    const auto mode = vectornav_emu_number(f[2], 10);
    const auto divisor = vectornav_emu_number(f[3], 10);
    const auto groups = vectornav_emu_number(f[4], 16);
    if (!mode || *mode < 0 || *mode > 3 || !divisor || *divisor < 1 || *divisor > 65535 ||
        !groups || *groups <= 0 || (*groups & ~long{kGroupCommon | kGroupImu}) != 0) {
      return vectornav_emu_error(kVectornavErrInvalidParameter);
    }
    const auto count = static_cast<std::size_t>(std::popcount(static_cast<unsigned>(*groups)));
    if (f.size() < 5 + count) return vectornav_emu_error(kVectornavErrNotEnoughParameters);
    if (f.size() > 5 + count) return vectornav_emu_error(kVectornavErrTooManyParameters);
    std::uint16_t words[2] = {0, 0};
    for (std::size_t i = 0; i < count; ++i) {
      const auto w = vectornav_emu_number(f[5 + i], 16);
      if (!w || *w <= 0 || *w > 0x7FFF) return vectornav_emu_error(kVectornavErrInvalidParameter);
      words[i] = static_cast<std::uint16_t>(*w);
    }
    const std::uint16_t common = (*groups & kGroupCommon) ? words[0] : 0;
    const std::uint16_t imu = (*groups & kGroupImu) ? words[(*groups & kGroupCommon) ? 1 : 0] : 0;
    try {
      (void)encode_binary_message(core::ImuSample{}, common, imu);  // fields it can output?
    } catch (const std::invalid_argument&) {
      return vectornav_emu_error(kVectornavErrInvalidParameter);
    }
    async_mode_ = static_cast<int>(*mode);
    divisor_ = static_cast<int>(*divisor);
    common_ = common;
    imu_ = imu;
    samples_ = 0;
  } else {
    return vectornav_emu_error(kVectornavErrInvalidRegister);
  }
  // A write is answered with the command echoed [UM001 §5.1.2: "$VNWRG,5,9600*60"].
  std::string echo = f[0];
  for (std::size_t i = 1; i < f.size(); ++i) echo += "," + f[i];
  return ascii_message(echo);
}

std::vector<std::uint8_t> VectornavEmulator::on_host_bytes(std::span<const std::uint8_t> bytes) {
  input_.insert(input_.end(), bytes.begin(), bytes.end());
  std::string reply;
  std::size_t at = 0;
  while (at < input_.size()) {
    if (input_[at] != '$') {
      ++at;  // not a command: the unit ignores it
      continue;
    }
    const std::span<const std::uint8_t> rest(input_.data() + at, input_.size() - at);
    AsciiMessage message;
    const Scan scan = parse_ascii(rest, true, message);
    if (scan == Scan::kIncomplete) break;
    if (scan == Scan::kOk) {
      reply += answer(message);
      at += message.size;
      continue;
    }
    // A whole line that is not a valid command (most likely its checksum): Invalid Checksum.
    const auto nl = std::find(rest.begin(), rest.end(), std::uint8_t{'\n'});
    if (nl == rest.end() || nl - rest.begin() >= static_cast<std::ptrdiff_t>(kMaxAsciiBytes)) {
      ++at;
      continue;
    }
    reply += vectornav_emu_error(kVectornavErrInvalidChecksum);
    at += static_cast<std::size_t>(nl - rest.begin()) + 1;
  }
  input_.erase(input_.begin(), input_.begin() + static_cast<std::ptrdiff_t>(at));
  return {reply.begin(), reply.end()};
}

std::vector<std::uint8_t> VectornavEmulator::on_sample(const core::ImuSample& sample) {
  if (async_mode_ == 0 || (common_ | imu_) == 0) return {};
  // The unit divides its 800 Hz IMU rate; a simulator sampling at another native rate gets the
  // same output rate by phase: a message whenever a whole output period has passed.
  bool due = false;
  if (std::abs(unit_.native_rate_hz - kVectornavEmuImuRateHz) < 1e-9 || unit_.native_rate_hz <= 0) {
    due = samples_ % static_cast<std::uint64_t>(divisor_) == 0;
  } else {
    const double outputs_per_sample = kVectornavEmuImuRateHz / divisor_ / unit_.native_rate_hz;
    const auto phase = [&](std::uint64_t n) {
      return std::floor(static_cast<double>(n) * outputs_per_sample + 1e-9);
    };
    due = samples_ == 0 || phase(samples_) != phase(samples_ - 1);
  }
  ++samples_;
  if (!due) return {};
  return encode_binary_message(sample, common_, imu_);
}

}  // namespace calstand::drivers::vectornav
