// The Epson IMU's side of the UART (docs/protocols.md, "Epson M-G3xx/G5xx"): what sim-station
// puts on the line and what the tests talk to besides the Python peer.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "drivers/epson_wire.hpp"

namespace calstand::drivers::epson {
namespace {

// Eight characters into four registers, first character in the low byte (PROD_ID1 "G3" =
// 0x3347), padded with spaces.
void epson_store_ascii(std::map<std::pair<int, int>, std::uint16_t>& regs, std::uint8_t first,
                       std::string text) {
  text.resize(8, ' ');
  for (int i = 0; i < 4; ++i) {
    const auto lo = static_cast<std::uint8_t>(text[static_cast<std::size_t>(2 * i)]);
    const auto hi = static_cast<std::uint8_t>(text[static_cast<std::size_t>(2 * i + 1)]);
    regs[{1, first + 2 * i}] = static_cast<std::uint16_t>((hi << 8) | lo);
  }
}

}  // namespace

Emulator::Emulator(const EmulatedUnit& unit)
    : model_(find_model(unit.model)), native_rate_hz_(unit.native_rate_hz) {
  if (model_ == nullptr) model_ = &models()[0];
  epson_store_ascii(registers_, kProdId1.address, model_->prod_id);
  epson_store_ascii(registers_, kSerialNum1.address, unit.serial);
  std::uint16_t version = 0;
  try {
    version = static_cast<std::uint16_t>(std::stoul(unit.firmware, nullptr, 16));
  } catch (const std::exception&) {
    version = 0;
  }
  registers_[{1, kVersion.address}] = version;
  // Power-on state: configuration mode, DOUT_RATE 0x01 (1000 Sps), a 16-tap moving average,
  // burst fields 0xF006, 16-bit, UART manual mode. The sheets' power-on values differ between
  // models; the dialogue writes every register it relies on, so these only need to differ
  // from what it writes for the tests to see the writes take effect.
  registers_[{1, kSmplCtrl.address}] = 0x0100;
  registers_[{1, kFilterCtrl.address}] = 0x0004;
  registers_[{1, kBurstCtrl1.address}] = 0xF006;
  registers_[{1, kBurstCtrl2.address}] = 0x0000;
  registers_[{1, kUartCtrl.address}] = 0x0000;
  registers_[{0, kDiagStat.address}] = 0x0000;
}

std::uint16_t Emulator::reg(std::uint8_t window, std::uint8_t address) const {
  const auto it = registers_.find({window, address});
  return it == registers_.end() ? 0 : it->second;
}

void Emulator::execute(std::uint8_t address, std::uint8_t data, std::vector<std::uint8_t>& reply) {
  if ((address & kWriteBit) == 0) {
    // A read: answered in configuration mode only (in UART auto mode while sampling the device
    // takes no reads, M-G365PD 6.2).
    if (sampling_) return;
    std::uint16_t value = reg(address == kWinCtrlAddress ? 0 : window_, address);
    if (address == kWinCtrlAddress) value = window_;
    if (window_ == 0 && address == kModeCtrl.address) value = sampling_ ? 0 : kModeStatConfig;
    reply.push_back(address);
    reply.push_back(static_cast<std::uint8_t>(value >> 8));
    reply.push_back(static_cast<std::uint8_t>(value & 0xFFu));
    reply.push_back(kDelimiter);
    return;
  }
  const auto a = static_cast<std::uint8_t>(address & 0x7Fu);
  if (a == kWinCtrlAddress) {
    window_ = data & 0x01u;
    return;
  }
  if (window_ == 0 && a == kModeCtrl.address + 1) {
    if (data == kModeCmdSampling) {
      sampling_ = true;
      native_index_ = 0;
    } else if (data == kModeCmdConfig) {
      sampling_ = false;
    }
    return;
  }
  if (sampling_) return;  // other writes are for configuration mode
  const auto even = static_cast<std::uint8_t>(a & 0xFEu);
  std::uint16_t& r = registers_[{window_, even}];
  r = (a & 1u) ? static_cast<std::uint16_t>((r & 0x00FFu) | (data << 8))
               : static_cast<std::uint16_t>((r & 0xFF00u) | data);
}

std::vector<std::uint8_t> Emulator::on_host_bytes(std::span<const std::uint8_t> bytes) {
  std::vector<std::uint8_t> reply;
  pending_.insert(pending_.end(), bytes.begin(), bytes.end());
  std::size_t i = 0;
  while (pending_.size() - i >= 3) {
    if (pending_[i + 2] != kDelimiter) {
      ++i;  // not a command: the device waits for the next delimiter-framed one
      continue;
    }
    execute(pending_[i], pending_[i + 1], reply);
    i += 3;
  }
  pending_.erase(pending_.begin(), pending_.begin() + static_cast<std::ptrdiff_t>(i));
  return reply;
}

std::vector<std::uint8_t> Emulator::on_sample(const core::ImuSample& sample) {
  if (!sampling_ || (reg(1, kUartCtrl.address) & kUartAuto) == 0) return {};
  const auto dout = static_cast<std::uint8_t>((reg(1, kSmplCtrl.address) >> 8) & 0x0Fu);
  double rate_hz = kBaseRateHz;
  for (const auto& r : output_rates()) {
    if (r.dout_code == dout) rate_hz = r.rate_hz;
  }
  const auto decimation = std::max<std::uint64_t>(
      1, static_cast<std::uint64_t>(std::llround(native_rate_hz_ / rate_hz)));
  const bool emit = native_index_ % decimation == 0;
  ++native_index_;
  if (!emit) return {};

  const int w = (reg(1, kBurstCtrl2.address) & kBurstCtrl2Value32) != 0 ? 32 : 16;
  BurstFields f;
  f.flags = kFlagNdMask;
  if (reg(0, kDiagStat.address) != 0) f.flags |= kFlagEa;
  f.temperature = temperature_raw(*model_, sample.temperature_c, w);
  for (int i = 0; i < 3; ++i) {
    f.gyro[i] = gyro_raw(*model_, sample.gyro_dps[i], w);
    f.accel[i] = accel_raw(*model_, sample.accel_mps2[i], w);
  }
  // COUNT from the device clock, at the base rate (CountStep::kBase, the reading this format
  // takes of the data sheet), modulo 2^16.
  f.count = static_cast<std::uint16_t>(
      static_cast<std::uint64_t>(std::llround(sample.device_time_s * kBaseRateHz)) & 0xFFFFu);
  return encode_burst(f, w);
}

}  // namespace calstand::drivers::epson
