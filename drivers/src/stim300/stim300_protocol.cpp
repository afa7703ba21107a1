// STIM300 datagrams: CRC-32, layouts, scale factors, status text (stim300_protocol.hpp; the
// citations are beside the declarations).
#include "drivers/stim300_protocol.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace calstand::drivers::stim300 {
namespace {

constexpr std::array<std::uint8_t, 8> kStim300Ids{kRate,         kRateAcc,        kRateIncl,
                                                  kRateAccIncl,  kRateTemp,       kRateAccTemp,
                                                  kRateInclTemp, kRateAccInclTemp};
constexpr std::array<const char*, 8> kStim300IdNames{
    "rate",      "rate_acc",      "rate_incl",      "rate_acc_incl",
    "rate_temp", "rate_acc_temp", "rate_incl_temp", "rate_acc_incl_temp"};
constexpr std::array<double, 5> kStim300Rates{125.0, 250.0, 500.0, 1000.0, 2000.0};
// The smallest reply datagram: identifier, one content byte, CRC [bytes].
constexpr std::size_t kStim300MinReply = 1 + 1 + kCrcSize;

void stim300_put_be(std::vector<std::uint8_t>& out, std::uint32_t value, int bytes) {
  for (int i = bytes - 1; i >= 0; --i) {
    out.push_back(static_cast<std::uint8_t>((value >> (8 * i)) & 0xFFu));
  }
}

std::uint32_t stim300_get_be(const std::uint8_t* p, int bytes) {
  std::uint32_t v = 0;
  for (int i = 0; i < bytes; ++i) v = (v << 8) | p[i];
  return v;
}

// Two's complement of a `bits`-wide field.
std::int32_t stim300_signed(std::uint32_t raw, int bits) {
  const std::uint32_t sign = 1u << (bits - 1);
  return static_cast<std::int32_t>(raw ^ sign) - static_cast<std::int32_t>(sign);
}

}  // namespace

namespace {

std::uint32_t stim300_crc_byte(std::uint32_t crc, std::uint8_t byte) {
  crc ^= std::uint32_t{byte} << 24;
  for (int bit = 0; bit < 8; ++bit) crc = (crc & 0x80000000u) ? (crc << 1) ^ 0x04C11DB7u : crc << 1;
  return crc;
}

}  // namespace

std::uint32_t crc32(std::span<const std::uint8_t> bytes) {
  // Bitwise: a 60-byte datagram at 2 kHz is 120 kB/s, far below where a table would matter.
  std::uint32_t crc = 0xFFFFFFFFu;
  for (std::uint8_t byte : bytes) crc = stim300_crc_byte(crc, byte);
  return crc;
}

std::uint32_t datagram_crc(std::span<const std::uint8_t> body) {
  std::uint32_t crc = crc32(body);
  for (std::size_t i = body.size(); i % 4 != 0; ++i) crc = stim300_crc_byte(crc, 0x00);
  return crc;
}

bool crc_matches(std::span<const std::uint8_t> bytes, std::size_t size) {
  if (size < kCrcSize + 1 || bytes.size() < size) return false;
  const std::size_t body = size - kCrcSize;
  return datagram_crc(bytes.first(body)) == stim300_get_be(bytes.data() + body, 4);
}

std::optional<DatagramLayout> datagram_layout(std::uint8_t id) {
  switch (id) {
    case kRate:
      return DatagramLayout{id, false, false, false};
    case kRateAcc:
      return DatagramLayout{id, true, false, false};
    case kRateIncl:
      return DatagramLayout{id, false, true, false};
    case kRateAccIncl:
      return DatagramLayout{id, true, true, false};
    case kRateTemp:
      return DatagramLayout{id, false, false, true};
    case kRateAccTemp:
      return DatagramLayout{id, true, false, true};
    case kRateInclTemp:
      return DatagramLayout{id, false, true, true};
    case kRateAccInclTemp:
      return DatagramLayout{id, true, true, true};
    default:
      return std::nullopt;
  }
}

std::span<const std::uint8_t> normal_datagram_ids() { return kStim300Ids; }

std::optional<std::uint8_t> datagram_id_from_name(const std::string& name) {
  for (std::size_t i = 0; i < kStim300Ids.size(); ++i) {
    if (name == kStim300IdNames[i] || name == fmt::format("0x{:02X}", kStim300Ids[i]) ||
        name == fmt::format("0x{:02x}", kStim300Ids[i])) {
      return kStim300Ids[i];
    }
  }
  return std::nullopt;
}

std::string datagram_name(std::uint8_t id) {
  for (std::size_t i = 0; i < kStim300Ids.size(); ++i) {
    if (kStim300Ids[i] == id) return fmt::format("0x{:02X} ({})", id, kStim300IdNames[i]);
  }
  return fmt::format("0x{:02X}", id);
}

std::vector<std::uint8_t> encode_datagram(const Datagram& d, bool termination) {
  const auto layout = datagram_layout(d.id);
  if (!layout) throw std::invalid_argument(fmt::format("STIM300: no datagram 0x{:02X}", d.id));
  const std::array<bool, 3> present{true, layout->acc, layout->incl};
  std::vector<std::uint8_t> out;
  out.reserve(layout->size() + 2);
  out.push_back(d.id);
  for (int g = 0; g < 3; ++g) {
    if (!present[static_cast<std::size_t>(g)]) continue;
    for (int a = 0; a < 3; ++a) {
      const std::int32_t v =
          std::clamp(d.value[static_cast<std::size_t>(g)][static_cast<std::size_t>(a)], -(1 << 23),
                     (1 << 23) - 1);
      stim300_put_be(out, static_cast<std::uint32_t>(v) & 0xFFFFFFu, 3);
    }
    out.push_back(d.status[static_cast<std::size_t>(g)]);
  }
  if (layout->temp) {
    for (int g = 0; g < 3; ++g) {
      if (!present[static_cast<std::size_t>(g)]) continue;
      for (int a = 0; a < 3; ++a) {
        const auto t = d.temp[static_cast<std::size_t>(g)][static_cast<std::size_t>(a)];
        stim300_put_be(out, static_cast<std::uint16_t>(t), 2);
      }
      out.push_back(d.temp_status[static_cast<std::size_t>(g)]);
    }
  }
  out.push_back(d.counter);
  stim300_put_be(out, d.latency_us, 2);
  stim300_put_be(out, datagram_crc(out), 4);
  if (termination) {
    out.push_back(kCr);
    out.push_back(kLf);
  }
  return out;
}

Datagram parse_datagram(std::span<const std::uint8_t> bytes, const DatagramLayout& layout) {
  Datagram d;
  d.id = layout.id;
  const std::array<bool, 3> present{true, layout.acc, layout.incl};
  const std::uint8_t* p = bytes.data() + 1;
  for (std::size_t g = 0; g < 3; ++g) {
    if (!present[g]) continue;
    for (std::size_t a = 0; a < 3; ++a, p += 3)
      d.value[g][a] = stim300_signed(stim300_get_be(p, 3), 24);
    d.status[g] = *p++;
  }
  if (layout.temp) {
    for (std::size_t g = 0; g < 3; ++g) {
      if (!present[g]) continue;
      for (std::size_t a = 0; a < 3; ++a, p += 2) {
        d.temp[g][a] = static_cast<std::int16_t>(stim300_signed(stim300_get_be(p, 2), 16));
      }
      d.temp_status[g] = *p++;
    }
  }
  d.counter = *p++;
  d.latency_us = static_cast<std::uint16_t>(stim300_get_be(p, 2));
  return d;
}

double gyro_counts_per_unit(GyroOutput output) {
  return output == GyroOutput::kAngularRate ? 16384.0 : 2097152.0;  // 2^14 per deg/s, 2^21 per deg
}

double accel_counts_per_unit(int range_g, AccelOutput output) {
  int exponent = 0;  // of the acceleration output, counts per g
  switch (range_g) {
    case 5:
      exponent = 20;
      break;
    case 10:
      exponent = 19;
      break;
    case 30:
      exponent = 18;
      break;
    case 80:
      exponent = 16;
      break;
    default:
      throw std::invalid_argument(fmt::format("STIM300: no {} g accelerometer", range_g));
  }
  // Incremental velocity [m/s] has 2^3 more counts per unit than acceleration [g].
  return std::ldexp(1.0, output == AccelOutput::kAcceleration ? exponent : exponent + 3);
}

double incl_counts_per_unit(AccelOutput output) {
  return output == AccelOutput::kAcceleration ? std::ldexp(1.0, 22) : std::ldexp(1.0, 25);
}

std::span<const double> sample_rates_hz() { return kStim300Rates; }

bool is_sample_rate(double rate_hz) {
  return std::any_of(kStim300Rates.begin(), kStim300Rates.end(),
                     [rate_hz](double r) { return std::abs(r - rate_hz) < 1e-9; });
}

bool is_startup_id(std::uint8_t id) {
  return kPartNumber.matches(id) || kSerialNumber.matches(id) || kConfiguration.matches(id);
}

std::vector<std::string> status_text(Group group, bool temperature, std::uint8_t status) {
  static constexpr std::array<const char*, 3> kGroup{"gyro", "accelerometer", "inclinometer"};
  static constexpr std::array<const char*, 5> kCondition{"error in measurement channel", "overload",
                                                         "outside operating conditions", "start-up",
                                                         "system integrity error"};
  std::vector<std::string> lines;
  if (status == 0) return lines;
  std::string channels;
  for (int axis = 0; axis < 3; ++axis) {
    if ((status & (1u << axis)) == 0) continue;
    if (!channels.empty()) channels += ",";
    channels += static_cast<char>('x' + axis);
  }
  const std::string who =
      fmt::format("{}{}{}{}", kGroup[static_cast<std::size_t>(group)],
                  temperature ? " temperature" : "", channels.empty() ? "" : " ", channels);
  for (int bit = 3; bit < 8; ++bit) {
    if (status & (1u << bit)) {
      lines.push_back(fmt::format("{}: {}", who, kCondition[static_cast<std::size_t>(bit - 3)]));
    }
  }
  if (lines.empty()) lines.push_back(fmt::format("{}: channel flag without a condition", who));
  return lines;
}

std::vector<std::uint8_t> encode_configuration(std::span<const std::uint8_t> config,
                                               bool termination) {
  std::vector<std::uint8_t> out(1, kConfiguration.id(termination));
  out.reserve(1 + config.size() + kCrcSize + 2);
  out.insert(out.end(), config.begin(), config.end());
  stim300_put_be(out, datagram_crc(out), 4);
  if (termination) {
    out.push_back(kCr);
    out.push_back(kLf);
  }
  return out;
}

std::vector<std::uint8_t> encode_digits_datagram(ReplyKind kind, const std::string& text,
                                                 bool termination) {
  std::vector<std::uint8_t> codes;
  for (char ch : text) {
    if (ch >= '0' && ch <= '9') codes.push_back(static_cast<std::uint8_t>(ch - '0'));
    if (ch >= 'A' && ch <= 'F') codes.push_back(static_cast<std::uint8_t>(ch - 'A' + 10));
    if (ch >= 'a' && ch <= 'f') codes.push_back(static_cast<std::uint8_t>(ch - 'a' + 10));
  }
  if (codes.empty() || codes.size() % 2 != 0) codes.push_back(0);
  std::vector<std::uint8_t> out(1, kind.id(termination));
  out.reserve(1 + codes.size() / 2 + kCrcSize + 2);
  for (std::size_t i = 0; i < codes.size(); i += 2) {
    out.push_back(static_cast<std::uint8_t>((codes[i] << 4) | codes[i + 1]));
  }
  stim300_put_be(out, datagram_crc(out), 4);
  if (termination) {
    out.push_back(kCr);
    out.push_back(kLf);
  }
  return out;
}

std::string digits_of(std::span<const std::uint8_t> datagram) {
  static constexpr const char* kHex = "0123456789ABCDEF";
  std::string text;
  if (datagram.size() <= 1 + kCrcSize) return text;
  for (std::uint8_t b : datagram.subspan(1, datagram.size() - 1 - kCrcSize)) {
    text.push_back(kHex[b >> 4]);
    text.push_back(kHex[b & 0x0F]);
  }
  return text;
}

ReplyScan scan_reply_at(std::span<const std::uint8_t> bytes) {
  if (bytes.empty()) return {};
  for (std::size_t size = kStim300MinReply; size <= kMaxReplySize; ++size) {
    if (size > bytes.size()) return {ScanResult::kNeedMore, 0, 0};
    if (crc_matches(bytes, size)) return {ScanResult::kFound, 0, size};
  }
  return {};
}

ReplyScan find_reply(std::span<const std::uint8_t> bytes, ReplyKind kind) {
  ReplyScan pending;
  for (std::size_t at = 0; at < bytes.size(); ++at) {
    if (!kind.matches(bytes[at])) continue;
    auto scan = scan_reply_at(bytes.subspan(at));
    if (scan.result == ScanResult::kFound) return {ScanResult::kFound, at, scan.size};
    if (scan.result == ScanResult::kNeedMore && pending.result == ScanResult::kNone) {
      pending = {ScanResult::kNeedMore, at, 0};
    }
  }
  return pending;
}

}  // namespace calstand::drivers::stim300
