#pragma once

// The Epson UART burst format's three parts (imu_wire_format.hpp): the decoder, the
// configuration dialogue and the device emulator (docs/protocols.md, "Epson M-G3xx/G5xx").

#include <atomic>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "drivers/epson_protocol.hpp"
#include "drivers/frame_hunt.hpp"
#include "drivers/imu_wire_format.hpp"

namespace calstand::drivers::epson {

/// Decodes the burst frames of the configured width. Hunts for 0x80; a candidate whose end byte
/// is not 0x0D (a frame of another length) is a length error, one whose checksum is wrong a
/// checksum error ("crc_errors"); either costs one byte. COUNT is unwrapped (mod 65536) into
/// sequence and device time; COUNT going back is a device restart (device time goes back, and
/// a report says so). A frame with EA set reports the device's all-error flag once per run of
/// such frames.
class Decoder final : public FrameDecoder {
 public:
  explicit Decoder(Options options);

  std::size_t feed(std::span<const std::uint8_t> bytes, std::vector<core::ImuSample>& out) override;
  std::map<std::string, std::uint64_t> counters() const override;
  void restart() override;
  std::vector<std::string> take_device_reports() override;
  /// Scales with the model the unit reported, unless the station file names one.
  void identified(const UnitIdentity& unit) override;
  /// Bytes held back waiting for the rest of a frame [bytes]. Every byte fed is in exactly one
  /// of a frame, garbage_bytes, start_bytes or buffered().
  std::size_t buffered() const { return hunt_.buffered(); }

 private:
  const ModelScale* model();
  void decode(const BurstFields& f, std::vector<core::ImuSample>& out);
  void note_count_step(std::uint64_t delta);
  static constexpr int kStepsBeforeReport = 16;

  Options options_;
  // The model the unit reported (identified()); the reader thread reads it while a reopen's
  // dialogue may set it again.
  std::atomic<const ModelScale*> identified_model_{nullptr};
  std::size_t frame_size_;
  std::uint64_t count_step_;  // COUNT ticks per output sample
  double count_rate_hz_;      // COUNT ticks per second
  FrameHunt hunt_;
  bool have_count_ = false;
  bool check_gap_ = false;
  std::uint16_t last_count_ = 0;
  std::uint64_t unwrapped_count_ = 0;
  bool error_flag_ = false;
  bool reported_no_model_ = false;
  bool reported_count_step_ = false;
  int steps_like_other_ = 0;
  std::vector<std::string> reports_;
  std::map<std::string, std::uint64_t> stats_;
};

/// The host's dialogue: configuration mode, identity (PROD_ID, VERSION, SERIAL_NUM), output
/// rate, filter, burst fields and widths, UART auto mode, each write read back, DIAG_STAT,
/// then sampling.
class Configurator final : public ImuConfigurator {
 public:
  explicit Configurator(const WireFormatSettings& settings);
  UnitIdentity configure(ByteTransport& link) override;

 private:
  std::uint16_t read(ByteTransport& link, const Register& reg);
  void write(ByteTransport& link, const Register& reg, std::uint16_t value);
  void write_byte(ByteTransport& link, std::uint8_t address, std::uint8_t value);
  void select_window(ByteTransport& link, std::uint8_t window);
  void enter_configuration(ByteTransport& link);
  void write_checked(ByteTransport& link, const Register& reg, std::uint16_t value,
                     std::uint16_t mask);

  WireFormatSettings settings_;
  Options options_;
  int window_ = -1;  // unknown until selected
};

/// The device's side: registers in two windows, configuration and sampling modes, UART auto
/// mode streaming bursts at DOUT_RATE. PROD_ID is unit.model when the table has it (else
/// G366PDG0, the first row); SERIAL_NUM holds the first 8 characters of unit.serial; VERSION is
/// unit.firmware read as hexadecimal ("0x0105"), else 0.
class Emulator final : public ImuDeviceEmulator {
 public:
  explicit Emulator(const EmulatedUnit& unit);
  std::vector<std::uint8_t> on_host_bytes(std::span<const std::uint8_t> bytes) override;
  std::vector<std::uint8_t> on_sample(const core::ImuSample& sample) override;

  /// A nonzero DIAG_STAT sets EA in every burst (tests).
  void set_diag_stat(std::uint16_t value) { registers_[{0, kDiagStat.address}] = value; }
  bool sampling() const { return sampling_; }

 private:
  std::uint16_t reg(std::uint8_t window, std::uint8_t address) const;
  void execute(std::uint8_t address, std::uint8_t data, std::vector<std::uint8_t>& reply);

  const ModelScale* model_;
  double native_rate_hz_;
  std::map<std::pair<int, int>, std::uint16_t> registers_;
  std::uint8_t window_ = 0;
  bool sampling_ = false;
  std::uint64_t native_index_ = 0;
  std::vector<std::uint8_t> pending_;
};

}  // namespace calstand::drivers::epson
