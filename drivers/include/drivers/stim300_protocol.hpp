#pragma once

// The Sensonor STIM300 wire format: datagram layouts, CRC-32, scale factors, status bits and
// the normal-mode commands. Source: Sensonor "ButterflyGyro STIM300 Inertia Measurement Unit"
// datasheet, TS1524 (rev. 27; cited per constant as "TS1524 <section>"); where the public sheet was
// not at hand to check a detail, the constant says "calstand reading" and docs/protocols.md lists
// it under "open details".

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace calstand::drivers::stim300 {

/// CRC-32 of the STIM300 datagrams (TS1524, "CRC"): polynomial 0x04C11DB7, initial value
/// 0xFFFFFFFF, no input or output reflection, no final XOR (the catalogue's CRC-32/MPEG-2).
/// Check value over ASCII "123456789": 0x0376E6E7.
std::uint32_t crc32(std::span<const std::uint8_t> bytes);

/// The CRC of a datagram body (identifier .. last content byte) padded with dummy bytes 0x00
/// to a multiple of 4 bytes, as TS1524 ("CRC") computes it: the dummy bytes are not sent.
std::uint32_t datagram_crc(std::span<const std::uint8_t> body);

/// Line termination after the CRC when the unit is configured for it (TS1524, "datagram
/// termination"): CR LF.
inline constexpr std::uint8_t kCr = 0x0D;
inline constexpr std::uint8_t kLf = 0x0A;
inline constexpr std::size_t kCrcSize = 4;  ///< [bytes], big-endian

/// Normal-mode datagram identifiers (TS1524, "Datagram identifier" table). The AUX variants
/// (0x98..0x9F, 0xA8..0xAF) and the superseded temperature identifiers 0x95..0x97 are not
/// decoded (a station unit streams no AUX input).
inline constexpr std::uint8_t kRate = 0x90;
inline constexpr std::uint8_t kRateAcc = 0x91;
inline constexpr std::uint8_t kRateIncl = 0x92;
inline constexpr std::uint8_t kRateAccIncl = 0x93;
inline constexpr std::uint8_t kRateTemp = 0x94;
inline constexpr std::uint8_t kRateAccTemp = 0xA5;
inline constexpr std::uint8_t kRateInclTemp = 0xA6;
inline constexpr std::uint8_t kRateAccInclTemp = 0xA7;

/// Reply / start-up datagrams (TS1524, "Init mode" and "Normal mode commands"): after power-on
/// or reset the unit sends its part number, serial number and configuration datagrams before
/// its normal-mode datagrams, and sends them again on the commands N, I, C. Each has one
/// identifier without and one with CR LF termination (calstand reading, docs/protocols.md "open
/// details": both are accepted, whichever the unit uses).
struct ReplyKind {
  std::uint8_t plain = 0;  ///< identifier without CR LF
  std::uint8_t crlf = 0;   ///< identifier with CR LF
  bool matches(std::uint8_t id) const { return id == plain || id == crlf; }
  std::uint8_t id(bool termination) const { return termination ? crlf : plain; }
};
inline constexpr ReplyKind kPartNumber{0xB1, 0xB3};
inline constexpr ReplyKind kSerialNumber{0xB5, 0xB7};
inline constexpr ReplyKind kConfiguration{0xBC, 0xBD};
inline constexpr ReplyKind kExtendedError{0xBE, 0xBF};
/// Whether `id` starts a part number, serial number or configuration datagram.
bool is_startup_id(std::uint8_t id);

/// Normal-mode commands (TS1524, "Normal mode commands"): ASCII, ended by CR.
inline constexpr const char* kCommandPartNumber = "N\r";
inline constexpr const char* kCommandSerialNumber = "I\r";
inline constexpr const char* kCommandConfiguration = "C\r";
inline constexpr const char* kCommandExtendedError = "T\r";
inline constexpr const char* kCommandReset = "R\r";
inline constexpr const char* kCommandServiceMode = "SERVICEMODE\r";

/// The longest reply datagram (identifier .. CRC) the dialogue looks for [bytes]; the reply
/// datagrams' lengths are found by their CRC (docs/protocols.md, "open details").
inline constexpr std::size_t kMaxReplySize = 64;

/// Which measurements a normal-mode datagram carries, and so its layout (TS1524, "Normal mode
/// datagram" tables): identifier; gyro x, y, z (24 bit each) and the gyro status byte; then
/// accelerometer, then inclinometer, each as three 24-bit fields and a status byte when present;
/// with temperatures, for each present group three 16-bit temperatures and a status byte; then
/// the 8-bit counter and the 16-bit latency [us]; the CRC-32; CR LF when configured.
struct DatagramLayout {
  std::uint8_t id = 0;
  bool acc = false;
  bool incl = false;
  bool temp = false;

  std::size_t groups() const { return 1 + (acc ? 1 : 0) + (incl ? 1 : 0); }
  /// Identifier .. latency [bytes] (what the CRC covers, before the dummy bytes).
  std::size_t body_size() const { return 1 + groups() * 10 + (temp ? groups() * 7 : 0) + 3; }
  /// Dummy bytes the CRC pads the body with to a multiple of 4 [bytes].
  std::size_t padding() const { return (4 - body_size() % 4) % 4; }
  /// The datagram on the line without termination [bytes].
  std::size_t size() const { return body_size() + kCrcSize; }
};

/// The layout of normal-mode datagram `id`; none for an identifier this decoder does not read.
std::optional<DatagramLayout> datagram_layout(std::uint8_t id);
/// The identifiers datagram_layout() knows, in table order.
std::span<const std::uint8_t> normal_datagram_ids();
/// "0x93" .. as station files may write them, and the names: "rate", "rate_acc", "rate_incl",
/// "rate_acc_incl", "rate_temp", "rate_acc_temp", "rate_incl_temp", "rate_acc_incl_temp".
std::optional<std::uint8_t> datagram_id_from_name(const std::string& name);
std::string datagram_name(std::uint8_t id);

/// Measurement groups of a datagram, in datagram order.
enum class Group { kGyro = 0, kAcc = 1, kIncl = 2 };

/// One normal-mode datagram as raw integers (the unit's counts).
struct Datagram {
  std::uint8_t id = kRateAccInclTemp;
  std::array<std::array<std::int32_t, 3>, 3> value{};  ///< [group][axis], 24-bit signed
  std::array<std::uint8_t, 3> status{};                ///< [group]
  std::array<std::array<std::int16_t, 3>, 3> temp{};   ///< [group][axis], 16-bit signed
  std::array<std::uint8_t, 3> temp_status{};           ///< [group]
  std::uint8_t counter = 0;
  std::uint16_t latency_us = 0;  ///< [us] from sampling to the datagram's transmission
};

/// The datagram on the line (CRC appended, CR LF when `termination`). Values are clamped to
/// the 24-bit field.
std::vector<std::uint8_t> encode_datagram(const Datagram& datagram, bool termination);
/// Reads a datagram of `layout` from `bytes` (at least layout.size() bytes; the CRC is not
/// checked here).
Datagram parse_datagram(std::span<const std::uint8_t> bytes, const DatagramLayout& layout);
/// Whether the CRC at the end of the first `size` bytes matches the bytes before it.
bool crc_matches(std::span<const std::uint8_t> bytes, std::size_t size);

/// Scale factors (TS1524, "Output scaling"/resolution tables): counts per output unit.
enum class GyroOutput { kAngularRate, kIncrement };    ///< [deg/s] or [deg] per sample
enum class AccelOutput { kAcceleration, kIncrement };  ///< [g] or [m/s] per sample
/// Counts per deg/s (rate, 2^14) or per deg (incremental angle, 2^21).
double gyro_counts_per_unit(GyroOutput output);
/// Counts per g (acceleration: 5 g 2^20, 10 g 2^19, 30 g 2^18, 80 g 2^16) or per m/s
/// (incremental velocity: 5 g 2^23, 10 g 2^22, 30 g 2^21, 80 g 2^19). Throws
/// std::invalid_argument for another range.
double accel_counts_per_unit(int range_g, AccelOutput output);
/// Inclinometer counts per g (2^22; incremental velocity 2^25 per m/s).
double incl_counts_per_unit(AccelOutput output);
/// Temperature counts per degC (2^8).
inline constexpr double kTempCountsPerDegC = 256.0;
/// The g of the sheet's [g] outputs: standard gravity [m/s^2] (calstand reading: TS1524 gives
/// outputs in g without a local value).
inline constexpr double kStandardGravity = 9.80665;

/// The sample rates the unit can be set to (TS1524, "Sample rate" in the configuration):
/// 125, 250, 500, 1000, 2000 Hz (and an external trigger, which calstand does not use).
std::span<const double> sample_rates_hz();
/// Whether the unit can sample at `rate_hz`.
bool is_sample_rate(double rate_hz);

/// The status byte's bits in the unit's words, for `group` ("gyro", "accelerometer",
/// "inclinometer", with "temperature" when `temperature`): bits 0..2 name the channels (x, y,
/// z) the condition bits refer to; bit 3 error in measurement channel, bit 4 overload, bit 5
/// outside operating conditions, bit 6 start-up, bit 7 system integrity error (TS1524,
/// "Status byte"). One line per condition: "gyro x: outside operating conditions". Nothing for
/// a zero byte.
std::vector<std::string> status_text(Group group, bool temperature, std::uint8_t status);
inline constexpr std::uint8_t kStatusStartup = 0x40;

/// A part number or serial number datagram: identifier, the digits packed two to a byte (one
/// 4-bit code each, 0..9 and A..F: TS1524, part number and serial number datagram tables; a
/// serial number is BCD), CRC-32, CR LF when `termination`. Characters other than hex digits
/// are left out; an odd count is padded with a 0 code.
std::vector<std::uint8_t> encode_digits_datagram(ReplyKind kind, const std::string& text,
                                                 bool termination);
/// The digits of a part number or serial number datagram (identifier .. CRC), as the sheet's
/// table turns each 4-bit code into ASCII ("0".."9", "A".."F").
std::string digits_of(std::span<const std::uint8_t> datagram);
/// The configuration datagram (the reply to C): identifier, the unit's configuration bytes
/// (calstand does not interpret them: docs/protocols.md, "open details"), CRC-32, CR LF.
inline constexpr std::size_t kConfigurationBytes = 16;
std::vector<std::uint8_t> encode_configuration(std::span<const std::uint8_t> config,
                                               bool termination);

/// Where a reply datagram `id` begins in `bytes` and how long it is (identifier .. CRC): the
/// first position holding `id` followed by a body whose CRC matches, trying each length up to
/// kMaxReplySize. kNeedMore when a candidate could still complete.
enum class ScanResult { kFound, kNeedMore, kNone };
struct ReplyScan {
  ScanResult result = ScanResult::kNone;
  std::size_t offset = 0;
  std::size_t size = 0;
};
/// Looks for a reply datagram starting exactly at bytes[0] (whose identifier is the caller's to
/// check).
ReplyScan scan_reply_at(std::span<const std::uint8_t> bytes);
/// Looks for a reply datagram of `kind` anywhere in `bytes`.
ReplyScan find_reply(std::span<const std::uint8_t> bytes, ReplyKind kind);

}  // namespace calstand::drivers::stim300
