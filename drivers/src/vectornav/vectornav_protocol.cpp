// The VectorNav codec: binary messages, ASCII commands, checksums and options
// (drivers/include/drivers/vectornav_protocol.hpp cites the manual beside each constant).
#include "drivers/vectornav_protocol.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <stdexcept>

#include "core/error.hpp"

namespace calstand::drivers::vectornav {
namespace {

// Field sizes by group bit and field bit [UM001 ch. 4, binary output field definitions]; 0 for
// fields reserved on the VN-100 (GPS time, position, velocity) or unknown to this decoder.
constexpr std::array<std::array<std::uint8_t, 15>, 8> kVectornavFieldSizes = {{
    // Common: TimeStartup, -, TimeSyncIn, YawPitchRoll, Quaternion, AngularRate, -, -, Accel,
    // Imu, MagPres, DeltaTheta, VpeStatus, SyncInCnt, -
    {8, 0, 8, 12, 16, 12, 0, 0, 12, 24, 20, 28, 2, 4, 0},
    // Time: TimeStartup, -, -, -, TimeSyncIn, -, -, SyncInCnt, SyncOutCnt
    {8, 0, 0, 0, 8, 0, 0, 4, 4, 0, 0, 0, 0, 0, 0},
    // IMU: ImuStatus, UncompMag, UncompAccel, UncompGyro, Temp, Pres, DeltaTheta, DeltaVel,
    // Mag, Accel, AngularRate
    {2, 12, 12, 12, 4, 4, 16, 12, 12, 12, 12, 0, 0, 0, 0},
    {},  // group 4: unused on the VN-100
    // Attitude: VpeStatus, YawPitchRoll, Quaternion, DCM, MagNed, AccelNed, LinearAccelBody,
    // LinearAccelNed, YprU
    {2, 12, 16, 36, 12, 12, 12, 12, 12, 0, 0, 0, 0, 0, 0},
    {},
    {},
    {},
}};

std::uint64_t vectornav_get_le(const std::uint8_t* p, int size_bytes) {
  std::uint64_t v = 0;
  for (int i = size_bytes - 1; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}

std::array<float, 3> vectornav_get_vec3(const std::uint8_t* p) {
  std::array<float, 3> v{};
  for (std::size_t i = 0; i < 3; ++i) {
    v[i] = std::bit_cast<float>(static_cast<std::uint32_t>(vectornav_get_le(p + 4 * i, 4)));
  }
  return v;
}

void vectornav_put_le(std::vector<std::uint8_t>& out, std::uint64_t v, int size_bytes) {
  for (int i = 0; i < size_bytes; ++i) out.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}

void vectornav_put_f32(std::vector<std::uint8_t>& out, double v) {
  vectornav_put_le(out, std::bit_cast<std::uint32_t>(static_cast<float>(v)), 4);
}

constexpr double kVectornavDegPerRad = 180.0 / 3.14159265358979323846;

void vectornav_put_gyro(std::vector<std::uint8_t>& out, const core::ImuSample& s) {
  for (int i = 0; i < 3; ++i) vectornav_put_f32(out, s.gyro_dps[i] / kVectornavDegPerRad);
}

void vectornav_put_accel(std::vector<std::uint8_t>& out, const core::ImuSample& s) {
  for (int i = 0; i < 3; ++i) vectornav_put_f32(out, s.accel_mps2[i]);
}

bool vectornav_is_hex(char c) {
  return (c >= '0' && c <= '9') || (c >= 'A' && c <= 'F') || (c >= 'a' && c <= 'f');
}

}  // namespace

std::size_t field_size_bytes(int group_bit, int bit) {
  if (group_bit < 0 || group_bit >= 8 || bit < 0 || bit >= 15) return 0;
  return kVectornavFieldSizes[static_cast<std::size_t>(group_bit)][static_cast<std::size_t>(bit)];
}

Scan parse_binary_header(std::span<const std::uint8_t> bytes, BinaryHeader& out) {
  if (bytes.size() < 2) return Scan::kIncomplete;
  out = BinaryHeader{};
  out.groups = bytes[1];
  // No groups, an extension byte (groups 8-14 are reserved) or an unused group: unmeasurable.
  if (out.groups == 0 || (out.groups & ~kGroupsKnown) != 0) return Scan::kInvalid;
  std::size_t at = 2;
  for (int g = 0; g < 8; ++g) {
    if ((out.groups & (1u << g)) == 0) continue;
    if (bytes.size() < at + 2) return Scan::kIncomplete;
    const auto word = static_cast<std::uint16_t>(vectornav_get_le(bytes.data() + at, 2));
    at += 2;
    // A group with no fields, or a continuation word (fields 16-30 are not defined on the
    // VN-100): unmeasurable.
    if (word == 0 || (word & kFieldExtension) != 0) return Scan::kInvalid;
    for (int bit = 0; bit < 15; ++bit) {
      if ((word & (1u << bit)) == 0) continue;
      const std::size_t size = field_size_bytes(g, bit);
      if (size == 0) return Scan::kInvalid;
      out.payload_bytes += size;
    }
    out.fields[static_cast<std::size_t>(g)] = word;
  }
  out.header_bytes = at;
  return Scan::kOk;
}

BinaryFields parse_binary_payload(std::span<const std::uint8_t> message,
                                  const BinaryHeader& header) {
  BinaryFields f;
  const std::uint8_t* p = message.data() + header.header_bytes;
  for (int g = 0; g < 8; ++g) {
    const std::uint16_t word = header.fields[static_cast<std::size_t>(g)];
    for (int bit = 0; bit < 15; ++bit) {
      if ((word & (1u << bit)) == 0) continue;
      const auto mask = static_cast<std::uint16_t>(1u << bit);
      if ((g == 0 && mask == kCommonTimeStartup) || (g == 1 && mask == kTimeTimeStartup)) {
        f.time_startup_ns = vectornav_get_le(p, 8);
      } else if (g == 0 && mask == kCommonAngularRate) {
        f.gyro_rps = vectornav_get_vec3(p);
      } else if (g == 0 && mask == kCommonAccel) {
        f.accel_mps2 = vectornav_get_vec3(p);
      } else if (g == 0 && mask == kCommonImu) {
        f.uncomp_accel_mps2 = vectornav_get_vec3(p);
        f.uncomp_gyro_rps = vectornav_get_vec3(p + 12);
      } else if (g == 2 && mask == kImuUncompAccel) {
        f.uncomp_accel_mps2 = vectornav_get_vec3(p);
      } else if (g == 2 && mask == kImuUncompGyro) {
        f.uncomp_gyro_rps = vectornav_get_vec3(p);
      } else if (g == 2 && mask == kImuTemp) {
        // One float (4 bytes): a vec3 read here ran 8 bytes past the field, and past the
        // message when Temp is its last field (found by AddressSanitizer).
        f.temperature_c = std::bit_cast<float>(static_cast<std::uint32_t>(vectornav_get_le(p, 4)));
      } else if (g == 2 && mask == kImuAccel) {
        f.accel_mps2 = vectornav_get_vec3(p);
      } else if (g == 2 && mask == kImuAngularRate) {
        f.gyro_rps = vectornav_get_vec3(p);
      }
      p += field_size_bytes(g, bit);
    }
  }
  return f;
}

std::vector<std::uint8_t> encode_binary_message(const core::ImuSample& sample, std::uint16_t common,
                                                std::uint16_t imu) {
  constexpr std::uint16_t kCommonKnown =
      kCommonTimeStartup | kCommonAngularRate | kCommonAccel | kCommonImu;
  constexpr std::uint16_t kImuKnown =
      kImuUncompAccel | kImuUncompGyro | kImuTemp | kImuAccel | kImuAngularRate;
  if ((common & ~kCommonKnown) != 0 || (imu & ~kImuKnown) != 0 || (common | imu) == 0) {
    throw std::invalid_argument("vectornav: cannot encode these fields");
  }
  std::vector<std::uint8_t> out{kSync, 0};
  if (common != 0) {
    out[1] |= kGroupCommon;
    vectornav_put_le(out, common, 2);
  }
  if (imu != 0) {
    out[1] |= kGroupImu;
    vectornav_put_le(out, imu, 2);
  }
  // Payload: groups in bit order, fields in bit order [UM001 §4.3].
  if (common & kCommonTimeStartup) {
    const double ns = std::max(0.0, std::round(sample.device_time_s * 1e9));
    vectornav_put_le(out, static_cast<std::uint64_t>(ns), 8);
  }
  if (common & kCommonAngularRate) vectornav_put_gyro(out, sample);
  if (common & kCommonAccel) vectornav_put_accel(out, sample);
  if (common & kCommonImu) {
    vectornav_put_accel(out, sample);
    vectornav_put_gyro(out, sample);
  }
  if (imu & kImuUncompAccel) vectornav_put_accel(out, sample);
  if (imu & kImuUncompGyro) vectornav_put_gyro(out, sample);
  if (imu & kImuTemp) vectornav_put_f32(out, sample.temperature_c);
  if (imu & kImuAccel) vectornav_put_accel(out, sample);
  if (imu & kImuAngularRate) vectornav_put_gyro(out, sample);
  const std::uint16_t crc = crc16(std::span(out).subspan(1));
  out.push_back(static_cast<std::uint8_t>(crc >> 8));  // most significant byte first
  out.push_back(static_cast<std::uint8_t>(crc & 0xFFu));
  return out;
}

std::uint8_t ascii_checksum(std::string_view body) {
  std::uint8_t sum = 0;
  for (char c : body) sum = static_cast<std::uint8_t>(sum ^ static_cast<std::uint8_t>(c));
  return sum;
}

std::string ascii_message(std::string_view body) {
  return fmt::format("${}*{:02X}\r\n", body, ascii_checksum(body));
}

Scan parse_ascii(std::span<const std::uint8_t> bytes, bool allow_bypass, AsciiMessage& out) {
  if (bytes.empty() || bytes[0] != '$') return Scan::kInvalid;
  std::size_t end = 1;
  for (; end < bytes.size(); ++end) {
    const std::uint8_t c = bytes[end];
    if (c == '\n') break;
    // A message is printable text ending in "\r\n": anything else is not one.
    if (c != '\r' && (c < 0x20 || c > 0x7E)) return Scan::kInvalid;
    if (end >= kMaxAsciiBytes) return Scan::kInvalid;
  }
  if (end == bytes.size()) return Scan::kIncomplete;
  std::string line(bytes.begin() + 1, bytes.begin() + static_cast<std::ptrdiff_t>(end));
  if (!line.empty() && line.back() == '\r') line.pop_back();
  const auto star = line.rfind('*');
  if (star == std::string::npos || line.size() != star + 3) return Scan::kInvalid;
  const std::string_view body(line.data(), star);
  const std::string sum = line.substr(star + 1);
  out = AsciiMessage{};
  if (sum == "XX") {
    if (!allow_bypass) return Scan::kInvalid;
    out.checksum_bypassed = true;
  } else {
    if (!vectornav_is_hex(sum[0]) || !vectornav_is_hex(sum[1])) return Scan::kInvalid;
    if (std::stoul(sum, nullptr, 16) != ascii_checksum(body)) return Scan::kInvalid;
  }
  if (body.empty() || body.find('$') != std::string_view::npos) return Scan::kInvalid;
  out.size = end + 1;
  std::size_t from = 0;
  for (;;) {
    const auto comma = body.find(',', from);
    out.fields.emplace_back(body.substr(from, comma - from));
    if (comma == std::string_view::npos) break;
    from = comma + 1;
  }
  return Scan::kOk;
}

std::string error_name(int code) {
  switch (code) {
    case 1:
      return "Hard Fault";
    case 2:
      return "Serial Buffer Overflow";
    case 3:
      return "Invalid Checksum";
    case 4:
      return "Invalid Command";
    case 5:
      return "Not Enough Parameters";
    case 6:
      return "Too Many Parameters";
    case 7:
      return "Invalid Parameter";
    case 8:
      return "Invalid Register";
    case 9:
      return "Unauthorized Access";
    case 10:
      return "Watchdog Reset";
    case 11:
      return "Output Buffer Overflow";
    case 12:
      return "Insufficient Baud Rate";
    case 255:
      return "Error Buffer Overflow";
    default:
      return "unknown error code";
  }
}

std::string error_text(const std::string& code_field) {
  int code = -1;
  if (!code_field.empty() && code_field.size() <= 3 &&
      std::all_of(code_field.begin(), code_field.end(),
                  [](char c) { return c >= '0' && c <= '9'; })) {
    code = std::stoi(code_field);
  }
  return fmt::format("$VNERR,{}: {}", code_field, error_name(code));
}

Options parse_options(const WireFormatSettings& settings) {
  Options o;
  const auto& j = settings.options;
  const auto where = [&](const std::string& key) { return settings.where + "." + key; };
  if (j.is_null()) return o;
  if (!j.is_object()) throw core::InputError(settings.where, "must be an object");
  for (const auto& [key, value] : j.items()) {
    if (key == "outputs") {
      if (value == "uncompensated") {
        o.compensated = false;
      } else if (value == "compensated") {
        o.compensated = true;
      } else {
        throw core::InputError(where(key), "must be \"uncompensated\" or \"compensated\"");
      }
    } else if (key == "port") {
      if (!value.is_number_integer() || (value != 1 && value != 2)) {
        throw core::InputError(where(key), "must be 1 or 2 (the unit's serial port)");
      }
      o.port = value.get<int>();
    } else if (key == "imu_rate_hz") {
      if (!value.is_number() || !(value.get<double>() > 0.0) || value.get<double>() > 100000.0) {
        throw core::InputError(where(key), "must be a rate in (0, 100000] Hz");
      }
      o.imu_rate_hz = value.get<double>();
    } else {
      throw core::InputError(where(key), "unknown option (outputs, port, imu_rate_hz)");
    }
  }
  return o;
}

std::uint16_t imu_fields(const Options& options) {
  return options.compensated
             ? static_cast<std::uint16_t>(kImuAccel | kImuAngularRate | kImuTemp)
             : static_cast<std::uint16_t>(kImuUncompAccel | kImuUncompGyro | kImuTemp);
}

int rate_divisor(const Options& options, double sample_rate_hz) {
  if (sample_rate_hz > 0.0) {
    const double ratio = options.imu_rate_hz / sample_rate_hz;
    const double divisor = std::round(ratio);
    if (divisor >= 1.0 && divisor <= 65535.0 && std::abs(ratio - divisor) <= 1e-9 * ratio) {
      return static_cast<int>(divisor);
    }
  }
  // The rates it can make: the IMU rate over a whole divisor; the whole-number ones are listed.
  std::string rates;
  for (int d = 1; d <= 65535 && options.imu_rate_hz / d >= 1.0; ++d) {
    const double r = options.imu_rate_hz / d;
    if (r != std::floor(r)) continue;
    rates += (rates.empty() ? "" : ", ") + fmt::format("{:g}", r);
  }
  throw DeviceConfigError(
      fmt::format("vectornav: {:g} Hz is not the {:g} Hz IMU rate divided by a whole RateDivisor "
                  "(1..65535); the unit can output {} Hz (or {:g} Hz / n)",
                  sample_rate_hz, options.imu_rate_hz, rates, options.imu_rate_hz));
}

std::string binary_output_body(const Options& options, int divisor) {
  return fmt::format("VNWRG,{},{},{},{:02X},{:04X},{:04X}", kRegBinaryOutput1, options.port,
                     divisor, kGroupCommon | kGroupImu, kCommonTimeStartup, imu_fields(options));
}

}  // namespace calstand::drivers::vectornav
