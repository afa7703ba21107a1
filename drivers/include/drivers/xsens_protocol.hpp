#pragma once

// The Xsens MTi wire protocol (Xbus messages, MTData2 packets): constants, message framing and
// checksum, the data identifiers used by calstand, value formats and the Error message's codes.
//
// Source: Xsens, "MT Low-Level Communication Protocol Documentation", document MT0101P (the
// revision we could read is cited in docs/protocols.md), sections "Xbus message structure",
// "Message identifiers" (the message reference), "MTData2" / "XDI" data identifiers, and
// "Error codes"; and the MTi Family Reference Manual (MT1600P, revision 2019.A, 4.3.2 Table 9:
// Acceleration 0x4020 in m/s^2, RateOfTurn 0x8020 in rad/s, in the sensor-fixed frame). Fixed-point
// formats: Xsens knowledge base, "An explanation of the MTi fixed point output formats"
// (base.xsens.com, article 115003494349). All multi-byte fields on the wire are big-endian
// (MT0101P, "Xbus message structure").

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "drivers/imu_wire_format.hpp"

namespace calstand::drivers::xsens {

// ---- Framing (MT0101P, "Xbus message structure") ----------------------------------------
inline constexpr std::uint8_t kPreamble = 0xFA;  ///< first byte of every message
inline constexpr std::uint8_t kBusId = 0xFF;     ///< BID of a stand-alone device ("master")
/// LEN 0xFF announces the extended length: two more bytes (big-endian) carry the data length.
inline constexpr std::uint8_t kExtendedLength = 0xFF;
/// Largest data length an extended-length message may announce [bytes] (MT0101P gives 2048
/// as the maximum message data length; a longer one is taken as a corrupted length field).
inline constexpr std::size_t kMaxDataLength = 2048;

// ---- Message identifiers (MT0101P, message reference; an ack is the request's MID + 1) ------
namespace mid {
inline constexpr std::uint8_t kReqDid = 0x00;           ///< ReqDID
inline constexpr std::uint8_t kDeviceId = 0x01;         ///< DeviceID: u32 (or u64) serial
inline constexpr std::uint8_t kGoToMeasurement = 0x10;  ///< GoToMeasurement
inline constexpr std::uint8_t kGoToMeasurementAck = 0x11;
inline constexpr std::uint8_t kReqFwRev = 0x12;        ///< ReqFWRev
inline constexpr std::uint8_t kFirmwareRev = 0x13;     ///< major, minor, revision[, build, svn]
inline constexpr std::uint8_t kReqProductCode = 0x1C;  ///< ReqProductCode
inline constexpr std::uint8_t kProductCode = 0x1D;     ///< ASCII product code
inline constexpr std::uint8_t kGoToConfig = 0x30;      ///< GoToConfig
inline constexpr std::uint8_t kGoToConfigAck = 0x31;
inline constexpr std::uint8_t kMtData2 = 0x36;                 ///< MTData2 measurement packet
inline constexpr std::uint8_t kWakeUp = 0x3E;                  ///< sent by the device at power-on
inline constexpr std::uint8_t kWakeUpAck = 0x3F;               ///< host: stay in config mode
inline constexpr std::uint8_t kError = 0x42;                   ///< Error: error code [+ details]
inline constexpr std::uint8_t kSetOutputConfiguration = 0xC0;  ///< also the request (no data)
inline constexpr std::uint8_t kOutputConfiguration = 0xC1;     ///< ack: the applied configuration
}  // namespace mid

// ---- Data identifiers of MTData2 (MT0101P, "XDI" table) ---------------------------------
// An XDI is a u16: bits 15..4 the data type (group in the high byte), bits 3..2 the coordinate
// system, bits 1..0 the value precision.
namespace xdi {
inline constexpr std::uint16_t kTemperature = 0x0810;     ///< 1 value [degC]
inline constexpr std::uint16_t kPacketCounter = 0x1020;   ///< u16, +1 per packet
inline constexpr std::uint16_t kSampleTimeFine = 0x1060;  ///< u32, 10 kHz ticks
inline constexpr std::uint16_t kAcceleration = 0x4020;    ///< 3 values [m/s^2]
inline constexpr std::uint16_t kRateOfTurn = 0x8020;      ///< 3 values [rad/s]
inline constexpr std::uint16_t kTypeMask = 0xFFF0;
inline constexpr std::uint16_t kPrecisionMask = 0x0003;
inline constexpr std::uint16_t kCoordinatesMask = 0x000C;
}  // namespace xdi

/// SampleTimeFine counts at 10 kHz (MT0101P, XDI 0x1060) [ticks/s].
inline constexpr double kSampleTimeFineHz = 10000.0;
/// The output frequency field of SetOutputConfiguration for "with every packet": MT0101P
/// gives 0xFFFF (and 0x0000) as "output at the highest rate"; used for the counters.
inline constexpr std::uint16_t kEveryPacket = 0xFFFF;

/// Value precision, XDI bits 1..0 (MT0101P, "XDI" format bits).
enum class Precision : std::uint8_t {
  kFloat32 = 0x0,  ///< IEEE 754 single
  kFp1220 = 0x1,   ///< signed fixed point 12.20 in 4 bytes
  kFp1632 = 0x2,   ///< signed fixed point 16.32 in 6 bytes (fraction u32, then integer i16)
  kFloat64 = 0x3,  ///< IEEE 754 double
};
/// Coordinate system, XDI bits 3..2 (MT0101P, XDI format bits): East-North-Up (default),
/// North-East-Down, North-West-Up.
enum class Coordinates : std::uint8_t { kEnu = 0x0, kNed = 0x4, kNwu = 0x8 };

/// Bytes of one value in `precision` (4, 4, 6, 8).
std::size_t value_size(Precision precision);
/// Appends `v` in `precision`, rounded (fixed point) or narrowed (float32) as the device does.
void put_value(std::vector<std::uint8_t>& out, double v, Precision precision);
/// The value at `p` in `precision`.
double get_value(const std::uint8_t* p, Precision precision);
/// What `v` becomes on the wire and back.
double quantise(double v, Precision precision);

/// Body axes of the emulated unit when it outputs in `coordinates`, from the ENU-default sensor
/// frame: NED turns the sensor frame 180 deg about x (x, -y, -z); ENU and NWU leave it. The MTi
/// family reference manual (MT1600P 2019.A, 4.3.2) puts calibrated data in the sensor frame and
/// does not say whether NED turns it: this is our model (docs/protocols.md), used only by the
/// emulator; the decoder takes the axes as sent.
std::array<double, 3> to_coordinates(Coordinates coordinates, const std::array<double, 3>& enu);

/// The byte that makes BID + MID + LEN (+ EXT LEN) + DATA + checksum sum to 0 mod 256.
std::uint8_t checksum_for(std::span<const std::uint8_t> bid_to_data);

/// One complete message: preamble, BID 0xFF, `mid`, length (extended above 254 bytes), data,
/// checksum.
std::vector<std::uint8_t> encode_message(std::uint8_t mid, std::span<const std::uint8_t> data = {});

/// A message read off the line.
struct Message {
  std::uint8_t mid = 0;
  std::vector<std::uint8_t> data;
};

/// What scan_message() found at the start of a buffer that begins with the preamble.
enum class ScanStatus {
  kMessage,      ///< a valid message of `size` bytes
  kIncomplete,   ///< could be a message: wait for more bytes
  kBadBusId,     ///< the byte after the preamble is not 0xFF
  kBadLength,    ///< extended length beyond kMaxDataLength
  kBadChecksum,  ///< complete but the sum is not 0
};
struct Scan {
  ScanStatus status = ScanStatus::kIncomplete;
  std::size_t size = 0;  ///< bytes of the message (kMessage)
  Message message;       ///< kMessage only
};
/// Looks at `bytes`, whose first byte is the preamble.
Scan scan_message(std::span<const std::uint8_t> bytes);

/// Every valid message in `bytes` (hunting past anything else), oldest first.
std::vector<Message> messages_in(std::span<const std::uint8_t> bytes);

/// The Error message's code as text, with the code: "Error 0x21: invalid parameter ...".
std::string error_text(std::span<const std::uint8_t> error_data);

/// One entry of SetOutputConfiguration: a data identifier and its output frequency [Hz].
struct OutputItem {
  std::uint16_t xdi = 0;
  std::uint16_t rate_hz = 0;  ///< kEveryPacket: with every packet
  bool operator==(const OutputItem&) const = default;
};
std::vector<std::uint8_t> encode_output_configuration(const std::vector<OutputItem>& items);
/// Nothing when the data is not a whole number of 4-byte entries.
std::optional<std::vector<OutputItem>> parse_output_configuration(
    std::span<const std::uint8_t> data);

/// The format's options (`connection.xsens`, schema `xsens_options`).
struct Options {
  Precision precision = Precision::kFloat32;    ///< "float_format"
  Coordinates coordinates = Coordinates::kEnu;  ///< "coordinates"
  std::uint16_t temperature_rate_hz = 0;        ///< "temperature_rate_hz", resolved
};
/// The highest temperature output rate calstand asks of a unit by default [Hz]: our cautious
/// assumption, no public maximum found (docs/protocols.md, "Xsens MTi", options).
inline constexpr std::uint16_t kMaxTemperatureRateHz = 400;
/// Reads settings.options with the defaults; throws core::InputError naming
/// settings.where + ".key" for what the schema cannot check (a temperature rate above the
/// sample rate or not dividing it).
Options parse_options(const WireFormatSettings& settings);
/// The SetOutputConfiguration calstand sends for `options` at `sample_rate_hz`.
std::vector<OutputItem> output_configuration(const Options& options, std::uint16_t sample_rate_hz);

}  // namespace calstand::drivers::xsens
