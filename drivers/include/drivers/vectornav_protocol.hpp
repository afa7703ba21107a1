#pragma once

// The VectorNav VN-100 wire format's codec: the binary output message, the ASCII register
// commands and their checksums, and the format's options (docs/protocols.md, "VectorNav").
//
// Source: VectorNav, "VN-100 User Manual", document UM001, revision 2.22 (firmware v2.1.0.0),
// cited as [UM001 §x]; where UM001's public text is silent, VectorNav "VN-200 User Manual"
// UM004, cited as [UM004 §x], which documents the same command set.

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/imu_sample.hpp"
#include "drivers/imu_frame.hpp"
#include "drivers/imu_wire_format.hpp"

namespace calstand::drivers::vectornav {

// --- Binary output message [UM001 §4.3 "Serial Output Message Format"] ----------------------
//   offset size field
//   0      1    sync 0xFA [UM001 §4.3.1]
//   1      1    groups: one bit per output group, bit 7 = another group byte follows [§4.3.2]
//   2      2n   one u16 field mask per group set, bit 15 = another word follows [§4.2.2]
//   ...    var  payload: the selected fields, groups in bit order, fields in bit order,
//               little-endian, IEEE 754 floats
//   N      2    CRC-16 over bytes 1..N-1, sent most significant byte first, so that the CRC
//               over bytes 1..N+1 (the message after its sync, CRC included) is 0 [UM001 §3.8.3]
inline constexpr std::uint8_t kSync = 0xFA;
inline constexpr std::size_t kCrcSize = 2;  ///< [bytes]

/// Output groups' bits in the group byte [UM001 §4.2.1 table "Output Group"]: group 1 Common
/// (bit 0), 2 Time (bit 1), 3 IMU (bit 2), 5 Attitude (bit 4); 4, 6, 7 unused on the VN-100.
inline constexpr std::uint8_t kGroupCommon = 0x01;
inline constexpr std::uint8_t kGroupTime = 0x02;
inline constexpr std::uint8_t kGroupImu = 0x04;
inline constexpr std::uint8_t kGroupAttitude = 0x10;
inline constexpr std::uint8_t kGroupsKnown = kGroupCommon | kGroupTime | kGroupImu | kGroupAttitude;

/// Fields of the Common group [UM001 §4.2.2 field table, column "Group 1 Common"; sizes from
/// chapter 4 binary output field definitions].
inline constexpr std::uint16_t kCommonTimeStartup = 1u << 0;  ///< u64 [ns] since start-up
inline constexpr std::uint16_t kCommonAngularRate = 1u << 5;  ///< 3 x f32 [rad/s], compensated
inline constexpr std::uint16_t kCommonAccel = 1u << 8;        ///< 3 x f32 [m/s^2], compensated
inline constexpr std::uint16_t kCommonImu = 1u << 9;          ///< 6 x f32: UncompAccel, UncompGyro
/// Fields of the Time group [UM001 §4.2.2, column "Group 2 Time"].
inline constexpr std::uint16_t kTimeTimeStartup = 1u << 0;  ///< u64 [ns] since start-up
/// Fields of the IMU group [UM001 §4.2.2, column "Group 3 IMU"; the worked example on p. 35
/// sets 0x000C for "Bit 2 - UncompAccel, Bit 3 - UncompGyro"].
inline constexpr std::uint16_t kImuUncompAccel = 1u << 2;   ///< 3 x f32 [m/s^2]
inline constexpr std::uint16_t kImuUncompGyro = 1u << 3;    ///< 3 x f32 [rad/s]
inline constexpr std::uint16_t kImuTemp = 1u << 4;          ///< f32 [degC]
inline constexpr std::uint16_t kImuAccel = 1u << 9;         ///< 3 x f32 [m/s^2], compensated
inline constexpr std::uint16_t kImuAngularRate = 1u << 10;  ///< 3 x f32 [rad/s], compensated
inline constexpr std::uint16_t kFieldExtension = 0x8000;    ///< another field word follows

/// Bytes of field `bit` of the group at `group_bit` (0 Common, 1 Time, 2 IMU, 4 Attitude) on a
/// VN-100 [UM001 ch. 4 field definitions]; 0 for a field this decoder does not know (reserved on
/// the VN-100, or of a later firmware), whose message it cannot measure.
std::size_t field_size_bytes(int group_bit, int bit);

/// CRC-16 of the binary message [UM001 §3.8.3 "16-bit CRC": CRC16-CCITT]: polynomial 0x1021,
/// initial value 0, no reflection, no final XOR (the XMODEM form). Check value over ASCII
/// "123456789" is 0x31C3.
inline std::uint16_t crc16(std::span<const std::uint8_t> bytes) { return crc16_ccitt(bytes, 0); }

/// The groups and field masks of a binary message's header.
struct BinaryHeader {
  std::uint8_t groups = 0;
  std::array<std::uint16_t, 8> fields{};  ///< by group bit; 0 for groups not set
  std::size_t header_bytes = 0;           ///< sync, group byte and field words [bytes]
  std::size_t payload_bytes = 0;          ///< [bytes]
  std::size_t message_bytes() const { return header_bytes + payload_bytes + kCrcSize; }
};

enum class Scan { kIncomplete, kInvalid, kOk };

/// Reads the header of the message starting at bytes[0] (the sync byte). kInvalid when the
/// groups or fields name something this decoder cannot size (an extension byte or word, an
/// unused group, a reserved field): the length of such a message is unknown.
Scan parse_binary_header(std::span<const std::uint8_t> bytes, BinaryHeader& out);

/// What a binary message carried (fields it did not carry stay empty).
struct BinaryFields {
  std::optional<std::uint64_t> time_startup_ns;
  std::optional<std::array<float, 3>> uncomp_gyro_rps, gyro_rps;      ///< [rad/s]
  std::optional<std::array<float, 3>> uncomp_accel_mps2, accel_mps2;  ///< [m/s^2]
  std::optional<float> temperature_c;
};

/// The fields of a complete, CRC-checked message described by `header`.
BinaryFields parse_binary_payload(std::span<const std::uint8_t> message,
                                  const BinaryHeader& header);

/// A binary message with the Common and IMU fields in `common` and `imu` (what the device puts
/// on the line for that configuration): gyro in rad/s, accel in m/s^2, temperature, all f32;
/// TimeStartup from sample.device_time_s in ns. Fields the codec cannot fill are refused
/// (std::invalid_argument): only TimeStartup, Imu, AngularRate, Accel (Common) and
/// UncompAccel, UncompGyro, Temp, Accel, AngularRate (IMU).
std::vector<std::uint8_t> encode_binary_message(const core::ImuSample& sample, std::uint16_t common,
                                                std::uint16_t imu);

// --- ASCII commands [UM001 §3.8, §5.1] ------------------------------------------------------
//   $<body>*HH\r\n, HH = 8-bit XOR of the body's bytes (between '$' and '*') in hexadecimal;
//   "*XX" asks the device to skip the check [UM001 §3.8.1 "Checksum Bypass"].
inline constexpr std::size_t kMaxAsciiBytes = 256;  ///< the device's input buffer [UM004 §4.5]

/// Register IDs [UM004 §5.2-5.5 (1-4), §5.7 (6); UM001 p. 35 example (75)].
inline constexpr int kRegModelNumber = 1;
inline constexpr int kRegHardwareRevision = 2;
inline constexpr int kRegSerialNumber = 3;
inline constexpr int kRegFirmwareVersion = 4;
inline constexpr int kRegAsyncDataOutputType = 6;  ///< ADOR; 0 = ASCII async output off
inline constexpr int kRegBinaryOutput1 = 75;       ///< "Config register for first output message"

/// The 8-bit checksum of `body` [UM001 §3.8.2]: XOR of its bytes.
std::uint8_t ascii_checksum(std::string_view body);
/// "$" + body + "*HH\r\n" with the checksum.
std::string ascii_message(std::string_view body);

/// An ASCII message found at bytes[0] == '$'.
struct AsciiMessage {
  std::size_t size = 0;             ///< bytes up to and including its end of line [bytes]
  std::vector<std::string> fields;  ///< body split at commas: "VNRRG", "01", "VN-100T-CR"
  bool checksum_bypassed = false;   ///< sent with "*XX"
};

/// Reads the ASCII message at bytes[0] ('$' ... "*HH" ... '\n'). kInvalid for a non-printable
/// byte, a missing or wrong checksum (unless `allow_bypass` and "XX"), or no end of line
/// within kMaxAsciiBytes.
Scan parse_ascii(std::span<const std::uint8_t> bytes, bool allow_bypass, AsciiMessage& out);

/// The meaning of a `$VNERR` code [UM004 §4.5 table 20 "Error Codes", codes 1-12; UM001's own
/// table was not in the public text consulted, so the shared command set is assumed to share
/// them; 255 "Error Buffer Overflow" is from VectorNav's later manuals], e.g. "Invalid Register".
/// An unknown code is passed on as "unknown error code" with its number.
std::string error_name(int code);
/// "$VNERR,08: Invalid Register" style text for a device report or a DeviceConfigError.
std::string error_text(const std::string& code_field);

// --- Options (`connection.vectornav`, schema vectornav_options) -----------------------------
struct Options {
  bool compensated = false;    ///< "outputs": "compensated" (else the raw "uncompensated")
  int port = 1;                ///< the unit's serial port the station listens on (AsyncMode)
  double imu_rate_hz = 800.0;  ///< the IMU rate the RateDivisor divides [Hz] [UM001 p. 35]
};

/// Reads settings.options; throws core::InputError naming settings.where + ".key".
Options parse_options(const WireFormatSettings& settings);

/// The IMU group's field mask the options select (with TimeStartup from the Common group).
std::uint16_t imu_fields(const Options& options);

/// RateDivisor for `sample_rate_hz`: imu_rate_hz / rate, a whole number 1..65535. Throws
/// DeviceConfigError naming the rates the unit can output otherwise.
int rate_divisor(const Options& options, double sample_rate_hz);

/// The body of the Binary Output Register 1 write for `options` at `divisor`:
/// "VNWRG,75,<AsyncMode>,<RateDivisor>,05,0001,<imu fields>" [UM001 p. 35 example
/// "$VNWRG,75,1,16,15,0001,000C,0014*XX": groups and fields in hexadecimal].
std::string binary_output_body(const Options& options, int divisor);

}  // namespace calstand::drivers::vectornav
