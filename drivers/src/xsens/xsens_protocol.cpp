// The Xsens Xbus message and MTData2 value codec (drivers/xsens_protocol.hpp). Written from
// MT0101P, "MT Low-Level Communication Protocol Documentation"; see the header for sections.
#include "drivers/xsens_protocol.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>

#include "core/error.hpp"

namespace calstand::drivers::xsens {
namespace {

// Xbus is big-endian (MT0101P, "Xbus message structure"): shifts make it so on any host.
void xsens_put_be(std::vector<std::uint8_t>& out, std::uint64_t v, int size_bytes) {
  for (int i = size_bytes - 1; i >= 0; --i) out.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}

std::uint64_t xsens_get_be(const std::uint8_t* p, int size_bytes) {
  std::uint64_t v = 0;
  for (int i = 0; i < size_bytes; ++i) v = (v << 8) | p[i];
  return v;
}

// Fixed point m.f: the integer round(v * 2^f), saturated to its m + f bits (a value outside the
// range cannot be sent; the device's own behaviour there is not documented, saturation is the
// cautious choice for a test station: the value stays at the rail and visibly wrong).
std::int64_t xsens_fixed(double v, int fraction_bits, int total_bits) {
  const double scaled = std::round(std::ldexp(v, fraction_bits));
  const double max = std::ldexp(1.0, total_bits - 1) - 1.0;
  const double min = -std::ldexp(1.0, total_bits - 1);
  if (!(scaled == scaled)) return 0;  // NaN: no fixed-point form
  return static_cast<std::int64_t>(std::clamp(scaled, min, max));
}

}  // namespace

std::size_t value_size(Precision precision) {
  switch (precision) {
    case Precision::kFloat32:
    case Precision::kFp1220:
      return 4;
    case Precision::kFp1632:
      return 6;
    case Precision::kFloat64:
      return 8;
  }
  return 4;
}

void put_value(std::vector<std::uint8_t>& out, double v, Precision precision) {
  switch (precision) {
    case Precision::kFloat32:
      xsens_put_be(out, std::bit_cast<std::uint32_t>(static_cast<float>(v)), 4);
      return;
    case Precision::kFp1220:
      xsens_put_be(out, static_cast<std::uint32_t>(xsens_fixed(v, 20, 32)), 4);
      return;
    case Precision::kFp1632: {
      // 48-bit two's complement value: the fractional 32 bits go first, then the 16-bit
      // integer part (Xsens knowledge base, fixed point article, "16.32").
      const auto raw = static_cast<std::uint64_t>(xsens_fixed(v, 32, 48));
      xsens_put_be(out, raw & 0xFFFFFFFFu, 4);
      xsens_put_be(out, (raw >> 32) & 0xFFFFu, 2);
      return;
    }
    case Precision::kFloat64:
      xsens_put_be(out, std::bit_cast<std::uint64_t>(v), 8);
      return;
  }
}

double get_value(const std::uint8_t* p, Precision precision) {
  switch (precision) {
    case Precision::kFloat32:
      return std::bit_cast<float>(static_cast<std::uint32_t>(xsens_get_be(p, 4)));
    case Precision::kFp1220:
      return std::ldexp(static_cast<double>(static_cast<std::int32_t>(
                            static_cast<std::uint32_t>(xsens_get_be(p, 4)))),
                        -20);
    case Precision::kFp1632: {
      const std::uint64_t fraction = xsens_get_be(p, 4);
      const auto integer =
          static_cast<std::int16_t>(static_cast<std::uint16_t>(xsens_get_be(p + 4, 2)));
      // integer * 2^32 + fraction is the 48-bit signed value; exact in a double (< 2^53).
      return std::ldexp(static_cast<double>(integer) * 4294967296.0 + static_cast<double>(fraction),
                        -32);
    }
    case Precision::kFloat64:
      return std::bit_cast<double>(xsens_get_be(p, 8));
  }
  return 0.0;
}

double quantise(double v, Precision precision) {
  std::vector<std::uint8_t> bytes;
  put_value(bytes, v, precision);
  return get_value(bytes.data(), precision);
}

std::array<double, 3> to_coordinates(Coordinates coordinates, const std::array<double, 3>& enu) {
  if (coordinates == Coordinates::kNed) return {enu[0], -enu[1], -enu[2]};
  return enu;
}

std::uint8_t checksum_for(std::span<const std::uint8_t> bid_to_data) {
  unsigned sum = 0;
  for (std::uint8_t b : bid_to_data) sum += b;
  return static_cast<std::uint8_t>((0x100u - (sum & 0xFFu)) & 0xFFu);
}

std::vector<std::uint8_t> encode_message(std::uint8_t mid, std::span<const std::uint8_t> data) {
  std::vector<std::uint8_t> out;
  out.reserve(data.size() + 7);
  out.push_back(kPreamble);
  out.push_back(kBusId);
  out.push_back(mid);
  if (data.size() < kExtendedLength) {
    out.push_back(static_cast<std::uint8_t>(data.size()));
  } else {
    out.push_back(kExtendedLength);
    xsens_put_be(out, data.size(), 2);
  }
  out.insert(out.end(), data.begin(), data.end());
  out.push_back(checksum_for(std::span(out).subspan(1)));
  return out;
}

Scan scan_message(std::span<const std::uint8_t> bytes) {
  Scan scan;
  if (bytes.size() < 2) return scan;
  if (bytes[1] != kBusId) {
    scan.status = ScanStatus::kBadBusId;
    return scan;
  }
  if (bytes.size() < 4) return scan;
  std::size_t header = 4;
  std::size_t length = bytes[3];
  if (length == kExtendedLength) {
    if (bytes.size() < 6) return scan;
    header = 6;
    length = static_cast<std::size_t>(xsens_get_be(bytes.data() + 4, 2));
    // Checked before waiting for the body: an impossible length must not stall the stream.
    if (length > kMaxDataLength) {
      scan.status = ScanStatus::kBadLength;
      return scan;
    }
  }
  const std::size_t size = header + length + 1;
  if (bytes.size() < size) return scan;
  unsigned sum = 0;
  for (std::size_t i = 1; i < size; ++i) sum += bytes[i];
  if ((sum & 0xFFu) != 0) {
    scan.status = ScanStatus::kBadChecksum;
    return scan;
  }
  scan.status = ScanStatus::kMessage;
  scan.size = size;
  scan.message.mid = bytes[2];
  scan.message.data.assign(bytes.begin() + static_cast<std::ptrdiff_t>(header),
                           bytes.begin() + static_cast<std::ptrdiff_t>(header + length));
  return scan;
}

std::vector<Message> messages_in(std::span<const std::uint8_t> bytes) {
  std::vector<Message> out;
  std::size_t at = 0;
  while (at < bytes.size()) {
    if (bytes[at] != kPreamble) {
      ++at;
      continue;
    }
    Scan scan = scan_message(bytes.subspan(at));
    if (scan.status == ScanStatus::kMessage) {
      out.push_back(std::move(scan.message));
      at += scan.size;
    } else if (scan.status == ScanStatus::kIncomplete) {
      break;
    } else {
      ++at;  // a bad candidate costs one byte
    }
  }
  return out;
}

std::string error_text(std::span<const std::uint8_t> error_data) {
  if (error_data.empty()) return "Error without an error code";
  const std::uint8_t code = error_data[0];
  // MT0101P, "Error codes" (the codes an MTi sends in an Error message); the texts are ours.
  const char* what = "unknown error code";
  switch (code) {
    case 0x03:
      what = "invalid period";
      break;
    case 0x04:
      what = "invalid message (not valid or not supported in this state)";
      break;
    case 0x1E:
      what = "timer overflow (sample period too short)";
      break;
    case 0x20:
      what = "invalid baud rate";
      break;
    case 0x21:
      what = "invalid parameter (not valid or out of range)";
      break;
    case 0x28:
      what = "device error";
      break;
    case 0x29:
      what = "data overflow (more data than the baud rate carries)";
      break;
    case 0x2A:
      what = "buffer overflow (sample buffer full)";
      break;
    default:
      break;
  }
  std::string text = fmt::format("Error 0x{:02X}: {}", code, what);
  if (error_data.size() > 1) {
    // Code 0x28 carries further device error data; shown as sent.
    text += " (details";
    for (std::size_t i = 1; i < error_data.size(); ++i)
      text += fmt::format(" {:02X}", error_data[i]);
    text += ")";
  }
  return text;
}

std::vector<std::uint8_t> encode_output_configuration(const std::vector<OutputItem>& items) {
  std::vector<std::uint8_t> out;
  for (const OutputItem& item : items) {
    xsens_put_be(out, item.xdi, 2);
    xsens_put_be(out, item.rate_hz, 2);
  }
  return out;
}

std::optional<std::vector<OutputItem>> parse_output_configuration(
    std::span<const std::uint8_t> data) {
  if (data.size() % 4 != 0) return std::nullopt;
  std::vector<OutputItem> items;
  for (std::size_t at = 0; at < data.size(); at += 4) {
    items.push_back({static_cast<std::uint16_t>(xsens_get_be(data.data() + at, 2)),
                     static_cast<std::uint16_t>(xsens_get_be(data.data() + at + 2, 2))});
  }
  return items;
}

Options parse_options(const WireFormatSettings& settings) {
  Options o;
  const nlohmann::json& j = settings.options;
  if (j.contains("float_format")) {
    const std::string f = j.at("float_format").get<std::string>();
    if (f == "float32")
      o.precision = Precision::kFloat32;
    else if (f == "fp1220")
      o.precision = Precision::kFp1220;
    else if (f == "fp1632")
      o.precision = Precision::kFp1632;
    else if (f == "float64")
      o.precision = Precision::kFloat64;
    else
      throw core::InputError(settings.where + ".float_format",
                             "one of float32, fp1220, fp1632, float64");
  }
  if (j.contains("coordinates")) {
    const std::string c = j.at("coordinates").get<std::string>();
    if (c == "enu")
      o.coordinates = Coordinates::kEnu;
    else if (c == "ned")
      o.coordinates = Coordinates::kNed;
    else if (c == "nwu")
      o.coordinates = Coordinates::kNwu;
    else
      throw core::InputError(settings.where + ".coordinates", "one of enu, ned, nwu");
  }
  const double rate = settings.sample_rate_hz;
  const bool integer_rate = rate >= 1.0 && rate < 65535.0 && rate == std::floor(rate);
  const auto sample_rate = integer_rate ? static_cast<std::uint16_t>(rate) : std::uint16_t{0};
  if (j.contains("temperature_rate_hz")) {
    const double t = j.at("temperature_rate_hz").get<double>();
    const std::string where = settings.where + ".temperature_rate_hz";
    if (!(t >= 1.0 && t == std::floor(t) && t < 65535.0)) {
      throw core::InputError(where, "a whole number of Hz (the device's frequency field)");
    }
    o.temperature_rate_hz = static_cast<std::uint16_t>(t);
    // Each sample carries the latest temperature, so a temperature packet must coincide with
    // an inertial one: its rate divides the sample rate.
    if (sample_rate != 0 &&
        (o.temperature_rate_hz > sample_rate || sample_rate % o.temperature_rate_hz != 0)) {
      throw core::InputError(where, fmt::format("must divide the sample rate {} Hz", sample_rate));
    }
  } else {
    // Default: the highest rate the unit allows, not above the sample rate, dividing it.
    const std::uint16_t cap = std::min<std::uint16_t>(sample_rate, kMaxTemperatureRateHz);
    for (std::uint16_t t = cap; t >= 1; --t) {
      if (sample_rate % t == 0) {
        o.temperature_rate_hz = t;
        break;
      }
    }
    if (o.temperature_rate_hz == 0) o.temperature_rate_hz = 1;
  }
  return o;
}

std::vector<OutputItem> output_configuration(const Options& options, std::uint16_t sample_rate_hz) {
  const auto format = static_cast<std::uint16_t>(static_cast<unsigned>(options.precision) |
                                                 static_cast<unsigned>(options.coordinates));
  return {
      {xdi::kPacketCounter, kEveryPacket},
      {xdi::kSampleTimeFine, kEveryPacket},
      {static_cast<std::uint16_t>(xdi::kAcceleration | format), sample_rate_hz},
      {static_cast<std::uint16_t>(xdi::kRateOfTurn | format), sample_rate_hz},
      // Temperature is a scalar: the coordinate bits mean nothing for it, only the precision.
      {static_cast<std::uint16_t>(xdi::kTemperature | static_cast<unsigned>(options.precision)),
       options.temperature_rate_hz},
  };
}

}  // namespace calstand::drivers::xsens
