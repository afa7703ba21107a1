// An emulated MTi (drivers/xsens_emulator.hpp), from MT0101P, "MT Low-Level Communication
// Protocol Documentation": the states, the messages it answers and the MTData2 packet.
#include "drivers/xsens_emulator.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <numbers>
#include <sstream>

namespace calstand::drivers::xsens {
namespace {

void xsens_emu_put_be(std::vector<std::uint8_t>& out, std::uint64_t v, int size_bytes) {
  for (int i = size_bytes - 1; i >= 0; --i) out.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}

std::uint32_t xsens_emu_serial(const std::string& serial) {
  // The unit's DeviceID in hex, as the configurator prints it; another text gets a stable hash.
  const bool hex = !serial.empty() && serial.size() <= 8 &&
                   std::all_of(serial.begin(), serial.end(),
                               [](char c) { return std::isxdigit(static_cast<unsigned char>(c)); });
  if (hex) return static_cast<std::uint32_t>(std::stoul(serial, nullptr, 16));
  std::uint32_t h = 2166136261u;  // FNV-1a
  for (char c : serial) h = (h ^ static_cast<std::uint8_t>(c)) * 16777619u;
  return h;
}

std::vector<std::uint8_t> xsens_emu_firmware(const std::string& firmware) {
  // "major.minor.revision" -> three bytes.
  std::vector<std::uint8_t> out;
  std::istringstream in(firmware);
  std::string part;
  while (out.size() < 3 && std::getline(in, part, '.')) {
    out.push_back(static_cast<std::uint8_t>(std::atoi(part.c_str())));
  }
  while (out.size() < 3) out.push_back(0);
  return out;
}

void xsens_emu_item(std::vector<std::uint8_t>& out, std::uint16_t id,
                    std::span<const double> values) {
  const auto precision = static_cast<Precision>(id & xdi::kPrecisionMask);
  xsens_emu_put_be(out, id, 2);
  out.push_back(static_cast<std::uint8_t>(values.size() * value_size(precision)));
  for (double v : values) put_value(out, v, precision);
}

}  // namespace

XsensEmulator::XsensEmulator(const EmulatedUnit& unit) : unit_(unit) {
  // The stored configuration a unit starts with: float32, ENU, at 100 Hz when the native rate
  // makes it (else the native rate).
  std::uint16_t rate = 100;
  if (divider(rate) == 0) rate = static_cast<std::uint16_t>(std::lround(unit_.native_rate_hz));
  config_ = {{xdi::kPacketCounter, kEveryPacket},
             {xdi::kSampleTimeFine, kEveryPacket},
             {xdi::kAcceleration, rate},
             {xdi::kRateOfTurn, rate},
             {xdi::kTemperature, rate}};
}

std::uint32_t XsensEmulator::divider(std::uint16_t rate_hz) const {
  const double native = unit_.native_rate_hz;
  if (rate_hz == 0 || rate_hz == kEveryPacket) return 1;
  const double n = native / rate_hz;
  if (n < 1.0 || std::abs(n - std::round(n)) > 1e-9) return 0;
  return static_cast<std::uint32_t>(std::lround(n));
}

std::vector<std::uint8_t> XsensEmulator::answer(const Message& m) {
  auto ack = [&](std::span<const std::uint8_t> data = {}) {
    return encode_message(static_cast<std::uint8_t>(m.mid + 1), data);
  };
  auto error = [](std::uint8_t code) {
    const std::uint8_t data[] = {code};
    return encode_message(mid::kError, data);
  };
  switch (m.mid) {
    case mid::kGoToConfig:
      measuring_ = false;
      return ack();
    case mid::kGoToMeasurement:
      measuring_ = true;
      return ack();
    case mid::kWakeUpAck:
      measuring_ = false;  // acknowledged WakeUp: the unit stays in config state
      return {};
    case mid::kReqDid: {
      std::vector<std::uint8_t> data;
      xsens_emu_put_be(data, xsens_emu_serial(unit_.serial), 4);
      return ack(data);
    }
    case mid::kReqProductCode: {
      const std::vector<std::uint8_t> data(unit_.model.begin(), unit_.model.end());
      return ack(data);
    }
    case mid::kReqFwRev:
      return ack(xsens_emu_firmware(unit_.firmware));
    case mid::kSetOutputConfiguration: {
      if (m.data.empty()) return ack(encode_output_configuration(config_));  // a request
      if (measuring_) return error(0x04);  // configuration only in config state
      const auto items = parse_output_configuration(m.data);
      if (!items) return error(0x21);
      std::uint16_t gyro_rate = 0, accel_rate = 0;
      for (const OutputItem& item : *items) {
        const auto type = static_cast<std::uint16_t>(item.xdi & xdi::kTypeMask);
        const auto coords = item.xdi & xdi::kCoordinatesMask;
        if (coords == xdi::kCoordinatesMask) return error(0x21);  // no fourth system
        if (type == xdi::kPacketCounter || type == xdi::kSampleTimeFine) {
          if (item.xdi != type) return error(0x21);  // integers have no format bits
          continue;
        }
        if (type != (xdi::kAcceleration & xdi::kTypeMask) &&
            type != (xdi::kRateOfTurn & xdi::kTypeMask) &&
            type != (xdi::kTemperature & xdi::kTypeMask)) {
          return error(0x21);  // an output this emulated unit does not have
        }
        if (divider(item.rate_hz) == 0) return error(0x21);  // a rate it cannot make
        if (type == (xdi::kTemperature & xdi::kTypeMask) && item.rate_hz != kEveryPacket &&
            item.rate_hz > kMaxTemperatureRateHz) {
          return error(0x21);
        }
        if (type == (xdi::kAcceleration & xdi::kTypeMask)) accel_rate = item.rate_hz;
        if (type == (xdi::kRateOfTurn & xdi::kTypeMask)) gyro_rate = item.rate_hz;
      }
      // The emulated packet carries one inertial sample: accel and gyro at one rate.
      if (accel_rate != gyro_rate) return error(0x21);
      config_ = *items;
      return ack(encode_output_configuration(config_));
    }
    default:
      return error(0x04);  // a message it does not implement
  }
}

std::vector<std::uint8_t> XsensEmulator::on_host_bytes(std::span<const std::uint8_t> bytes) {
  // A unit the host already talks to has powered up long ago: no WakeUp any more.
  powered_ = true;
  pending_.insert(pending_.end(), bytes.begin(), bytes.end());
  std::vector<std::uint8_t> out;
  std::size_t at = 0;
  while (at < pending_.size()) {
    if (pending_[at] != kPreamble) {
      ++at;
      continue;
    }
    Scan scan = scan_message(std::span(pending_).subspan(at));
    if (scan.status == ScanStatus::kIncomplete) break;
    if (scan.status != ScanStatus::kMessage) {
      ++at;  // a corrupted message is ignored, as by the device
      continue;
    }
    at += scan.size;
    const auto reply = answer(scan.message);
    out.insert(out.end(), reply.begin(), reply.end());
  }
  pending_.erase(pending_.begin(), pending_.begin() + static_cast<std::ptrdiff_t>(at));
  return out;
}

std::vector<std::uint8_t> XsensEmulator::on_sample(const core::ImuSample& sample) {
  std::vector<std::uint8_t> out;
  if (!powered_) {
    powered_ = true;
    out = encode_message(mid::kWakeUp);  // power-on; unanswered, the unit goes on measuring
  }
  if (!measuring_) return out;
  std::uint32_t inertial_div = 0;
  for (const OutputItem& item : config_) {
    const auto type = item.xdi & xdi::kTypeMask;
    if (type == (xdi::kRateOfTurn & xdi::kTypeMask)) inertial_div = divider(item.rate_hz);
  }
  if (inertial_div == 0 || sample.sequence % inertial_div != 0) return out;

  std::vector<std::uint8_t> data;
  for (const OutputItem& item : config_) {
    const auto type = static_cast<std::uint16_t>(item.xdi & xdi::kTypeMask);
    const auto coords = static_cast<Coordinates>(item.xdi & xdi::kCoordinatesMask);
    if (type == xdi::kPacketCounter) {
      // One count per packet sent: the native counter over the decimation.
      xsens_emu_put_be(data, xdi::kPacketCounter, 2);
      data.push_back(2);
      xsens_emu_put_be(data, (sample.sequence / inertial_div) & 0xFFFFu, 2);
    } else if (type == xdi::kSampleTimeFine) {
      xsens_emu_put_be(data, xdi::kSampleTimeFine, 2);
      data.push_back(4);
      const auto ticks =
          static_cast<std::uint64_t>(std::llround(sample.device_time_s * kSampleTimeFineHz));
      xsens_emu_put_be(data, ticks & 0xFFFFFFFFu, 4);
    } else if (type == (xdi::kAcceleration & xdi::kTypeMask)) {
      const auto a = to_coordinates(
          coords, {sample.accel_mps2.x(), sample.accel_mps2.y(), sample.accel_mps2.z()});
      xsens_emu_item(data, item.xdi, a);
    } else if (type == (xdi::kRateOfTurn & xdi::kTypeMask)) {
      constexpr double kRadPerDeg = std::numbers::pi / 180.0;
      const auto w = to_coordinates(
          coords, {sample.gyro_dps.x() * kRadPerDeg, sample.gyro_dps.y() * kRadPerDeg,
                   sample.gyro_dps.z() * kRadPerDeg});
      xsens_emu_item(data, item.xdi, w);
    } else if (type == (xdi::kTemperature & xdi::kTypeMask)) {
      const std::uint32_t div = divider(item.rate_hz);
      if (div != 0 && sample.sequence % div == 0) {
        const double t[] = {sample.temperature_c};
        xsens_emu_item(data, item.xdi, t);
      }
    }
  }
  const auto packet = encode_message(mid::kMtData2, data);
  out.insert(out.end(), packet.begin(), packet.end());
  return out;
}

}  // namespace calstand::drivers::xsens
