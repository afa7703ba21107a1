#pragma once

// The Epson M-G3xx/G5xx IMU UART protocol (docs/protocols.md, "Epson M-G3xx/G5xx"): register
// read and write commands, the burst frame, the models' scale factors and the output rates.
//
// Sources (public data sheets of Seiko Epson Corporation):
//   [G365]  "IMU M-G365PD Data Sheet", Rev.20190905: the register map (WIN_CTRL, MODE_CTRL,
//           DIAG_STAT, FLAG, COUNT, SMPL_CTRL, FILTER_CTRL, UART_CTRL, BURST_CTRL1/2, PROD_ID,
//           VERSION, SERIAL_NUM), the UART command format, the DOUT_RATE table with its
//           recommended filter settings, the sensor specification table (scale factors).
//           Cited by register name: the section numbers were not available to check here.
//   [G362]  "IMU M-G362PDC1 Data Sheet", Rev.20131217: Table 6.10/6.11 (read command and
//           response), Table 6.14 (UART data packet format, burst/auto mode), 7.8/7.9 (32-bit
//           output = 16-bit value * 65536).
//   [G366]  "IMU M-G366PDG0 Data Sheet"; [G370] "IMU M-G370PD Data Sheet" (PDF1/PDS0/PDG0/
//           PDT0); [G330] "IMU M-G330PDG0 Data Sheet"; [G354] "IMU M-G354PDH0 Data Sheet";
//           [G570] "IMU M-G570PR Data Sheet": each model's sensor specification table.
// The register addresses and the burst layout are common to the family; what differs per model
// is a row of kEpsonModels.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "drivers/imu_wire_format.hpp"

namespace calstand::drivers::epson {

inline constexpr std::uint8_t kDelimiter = 0x0D;    ///< ends every command and reply [G362 6.2]
inline constexpr std::uint8_t kBurstHeader = 0x80;  ///< first byte of a burst frame [G362 T6.14]
inline constexpr std::uint8_t kWriteBit = 0x80;     ///< set in the address of a write [G365 6.2]
inline constexpr double kBaseRateHz = 2000.0;       ///< internal sampling rate [G365 SMPL_CTRL]

/// A 16-bit register: its (even) address and the window it sits in (WIN_CTRL) [G365 ch. 8].
struct Register {
  std::uint8_t address;
  std::uint8_t window;
  const char* name;
};

inline constexpr Register kModeCtrl{0x02, 0, "MODE_CTRL"};      ///< bits 9:8 MODE_CMD, 10 MODE_STAT
inline constexpr Register kDiagStat{0x04, 0, "DIAG_STAT"};      ///< diagnosis result (0 = no error)
inline constexpr Register kFlag{0x06, 0, "FLAG"};               ///< ND flags 15:9, EA bit 0
inline constexpr Register kCount{0x0A, 0, "COUNT"};             ///< sampling counter
inline constexpr Register kSigCtrl{0x00, 1, "SIG_CTRL"};        ///< ND flag enables
inline constexpr Register kMscCtrl{0x02, 1, "MSC_CTRL"};        ///< DRDY, EXT, self test
inline constexpr Register kSmplCtrl{0x04, 1, "SMPL_CTRL"};      ///< bits 11:8 DOUT_RATE
inline constexpr Register kFilterCtrl{0x06, 1, "FILTER_CTRL"};  ///< 4:0 FILTER_SEL, 5 FILTER_STAT
inline constexpr Register kUartCtrl{0x08, 1, "UART_CTRL"};      ///< bit 0 UART_AUTO, 1 AUTO_START
inline constexpr Register kGlobCmd{0x0A, 1, "GLOB_CMD"};        ///< bit 10 NOT_READY, 7 SOFT_RST
inline constexpr Register kBurstCtrl1{0x0C, 1, "BURST_CTRL1"};  ///< which fields are output
inline constexpr Register kBurstCtrl2{0x0E, 1, "BURST_CTRL2"};  ///< 32-bit widths
inline constexpr Register kProdId1{0x6A, 1, "PROD_ID1"};  ///< PROD_ID1..4 at 0x6A..0x70: ASCII
inline constexpr Register kVersion{0x72, 1, "VERSION"};   ///< firmware version
inline constexpr Register kSerialNum1{0x74, 1, "SERIAL_NUM1"};  ///< SERIAL_NUM1..4 0x74..0x7A
inline constexpr std::uint8_t kWinCtrlAddress = 0x7E;           ///< WIN_CTRL, in both windows

// Values written [G365 ch. 8].
inline constexpr std::uint8_t kModeCmdSampling = 0x01;    ///< MODE_CTRL high byte: go to sampling
inline constexpr std::uint8_t kModeCmdConfig = 0x02;      ///< MODE_CTRL high byte: go to config
inline constexpr std::uint16_t kModeStatConfig = 0x0400;  ///< MODE_CTRL bit 10: in config mode
inline constexpr std::uint8_t kUartAuto = 0x01;           ///< UART_CTRL low byte: auto mode on
inline constexpr std::uint16_t kFilterStatBusy = 0x0020;  ///< FILTER_CTRL bit 5: still setting
/// BURST_CTRL1: high byte FLAG_OUT(7) TEMP_OUT(6) GYRO_OUT(5) ACCL_OUT(4); low byte COUNT_OUT(1)
/// CHKSM_OUT(0). The frame calstand asks for: flags, temperature, gyro, accel, count, checksum.
inline constexpr std::uint16_t kBurstCtrl1Value = 0xF003;
/// BURST_CTRL2 high byte: TEMP_BIT(6) GYRO_BIT(5) ACCL_BIT(4) select 32-bit output.
inline constexpr std::uint16_t kBurstCtrl2Value32 = 0x7000;
inline constexpr std::uint16_t kFlagEa = 0x0001;  ///< FLAG bit 0: EA, all error (DIAG_STAT != 0)
inline constexpr std::uint16_t kFlagNdMask = 0xFE00;  ///< FLAG bits 15:9: ND temp, gyro, accel

/// "address, 0x00, 0x0D": read the register at `address` of the selected window [G362 T6.10].
std::vector<std::uint8_t> read_command(std::uint8_t address);
/// "address | 0x80, data, 0x0D": write one byte [G365 6.2]; a 16-bit register is two writes,
/// its low byte at the even address, its high byte at address + 1.
std::vector<std::uint8_t> write_command(std::uint8_t address, std::uint8_t data);
/// The reply to read_command(address), "address, data hi, data lo, 0x0D" [G362 T6.11], when it
/// ends `received` (a reply is the newest thing the device sent: it streams nothing in
/// configuration mode). Nothing otherwise.
std::optional<std::uint16_t> find_read_reply(std::span<const std::uint8_t> received,
                                             std::uint8_t address);

/// One model's scale factors (each model's data sheet, sensor specification table). For 32-bit
/// output every factor is divided by 65536 ([G362] 7.8, 7.9).
struct ModelScale {
  const char* prod_id;      ///< what PROD_ID1..4 read, e.g. "G366PDG0"
  const char* source;       ///< the data sheet the row comes from
  double gyro_dps_per_lsb;  ///< 16-bit [deg/s / LSB]
  double accel_mg_per_lsb;  ///< 16-bit [mG / LSB]
  double temp_c_per_lsb;    ///< 16-bit temperature slope [degC / LSB]
  double temp_lsb_at_25c;   ///< 16-bit reading at 25 degC [LSB]
};

/// Every model in the table, in one place (epson_models.cpp).
std::span<const ModelScale> models();
/// The row for PROD_ID `prod_id`, or null.
const ModelScale* find_model(const std::string& prod_id);
/// "G330PDG0, G354PDH0, ..." for errors.
std::string model_names();

/// One DOUT_RATE setting (SMPL_CTRL bits 11:8) and the shortest moving average the data sheet
/// recommends for it (FILTER_SEL TAP count).
struct OutputRate {
  double rate_hz;
  std::uint8_t dout_code;
  int recommended_taps;
};
std::span<const OutputRate> output_rates();
/// The setting that makes `rate_hz` exactly, or null.
const OutputRate* find_output_rate(double rate_hz);
/// "2000, 1000, 500, ... Hz" for errors.
std::string output_rate_names();

/// The FILTER_SEL code of a filter name: "moving_average_N" (N = 0, 2, 4, ... 128) or
/// "kaiser_N_fcF" (N = 32, 64, 128; F = 50, 100, 200, 400) [G365 FILTER_CTRL]. Null if unknown.
std::optional<std::uint8_t> filter_code(const std::string& name);
/// FILTER_SEL code of a moving average of `taps`.
std::uint8_t moving_average_code(int taps);

/// Does COUNT count output samples or internal samples at kBaseRateHz?
enum class CountStep { kBase, kOutput };

/// `connection.epson` of a station file (schema epson_options), checked against the rate.
struct Options {
  std::string model;  ///< PROD_ID of the model; empty = as the device reports it
  int width_bits = 32;
  std::uint8_t filter_code = 0;
  CountStep count_step = CountStep::kBase;
  const OutputRate* rate = nullptr;  ///< null when the rate is not a DOUT_RATE rate

  /// Throws core::InputError naming settings.where + ".key"; with `require_rate`, also
  /// settings.where + ".sample_rate_hz" for a rate DOUT_RATE cannot make (the configurator
  /// leaves that to configure(), which refuses it as the device would).
  static Options from_settings(const WireFormatSettings& settings, bool require_rate = true);
};

/// The decoded fields of a burst frame (raw device counts). For 16-bit output the values are
/// the 16-bit registers; for 32-bit output they are the 32-bit value (HIGH << 16 | LOW).
struct BurstFields {
  std::uint16_t flags = 0;
  std::int32_t temperature = 0;
  std::int32_t gyro[3] = {0, 0, 0};
  std::int32_t accel[3] = {0, 0, 0};
  std::uint16_t count = 0;
};

/// Bytes of a burst frame with kBurstCtrl1Value at `width_bits`: header, flags (2), temperature,
/// gyro x/y/z, accel x/y/z (2 or 4 each), count (2), checksum (2), end (1). 22 or 36.
std::size_t burst_size(int width_bits);
/// The 16-bit sum of the big-endian 16-bit words from the flags through the count, i.e. of
/// `words` (an even number of bytes) [G365 6.3, CHECKSUM].
std::uint16_t burst_checksum(std::span<const std::uint8_t> words);
/// A whole frame, checksum and end byte included.
std::vector<std::uint8_t> encode_burst(const BurstFields& fields, int width_bits);
/// The fields of a frame of burst_size(width_bits) bytes whose header, end and checksum are
/// right; nothing otherwise.
std::optional<BurstFields> parse_burst(std::span<const std::uint8_t> frame, int width_bits);

/// Physical values of raw fields, per the model's row and the width.
double gyro_dps(const ModelScale& m, std::int32_t raw, int width_bits);
double accel_mps2(const ModelScale& m, std::int32_t raw, int width_bits);
double temperature_c(const ModelScale& m, std::int32_t raw, int width_bits);
/// The raw value nearest `value` (saturated to the width), for the emulator.
std::int32_t gyro_raw(const ModelScale& m, double dps, int width_bits);
std::int32_t accel_raw(const ModelScale& m, double mps2, int width_bits);
std::int32_t temperature_raw(const ModelScale& m, double celsius, int width_bits);

inline constexpr double kStandardGravity = 9.80665;  ///< [m/s^2 per G] for the mG scale

}  // namespace calstand::drivers::epson
