#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/clock.hpp"
#include "core/station_config.hpp"
#include "drivers/imu_frame.hpp"
#include "drivers/imu_wire_format.hpp"
#include "drivers/serial_port.hpp"
#include "drivers/streaming_imu.hpp"

namespace calstand::drivers {

/// `connection` of an IMU with backend "serial" (docs/protocols.md):
///   {"path": "/dev/ttyUSB0", "baud": 921600, "parity": "none", "format": "xsens",
///    "sample_rate_hz": 400, "xsens": {...the format's own options...}}
struct SerialImuConnection {
  SerialOptions serial;
  std::string format = "calstand";  ///< wire format (imu_wire_format.hpp)
  /// The output rate asked of the device, the format's options (`connection.<format>`) and
  /// where they sit, for errors.
  WireFormatSettings settings;
  /// The calstand frame's counter wraps to 0 here (`sequence_modulus`); other formats say
  /// themselves (ImuWireFormat::sequence_modulus).
  std::uint64_t sequence_modulus = std::uint64_t{1} << 32;

  /// Throws core::InputError naming `where`.field (e.g. "imus[0].connection.baud").
  static SerialImuConnection from_json(const nlohmann::json& connection, const std::string& where);
};

/// An IMU streaming frames over a byte link (a serial line in the lab; a pseudo-terminal from
/// `calstand sim-station`), in any wire format (imu_wire_format.hpp). configure() opens the
/// link and runs the format's dialogue (output rate and fields, identity); the reader
/// (StreamingImu) decodes frames, stamps each sample on the station clock and buffers it for
/// poll(). Decoder faults (checksum and length errors, garbage) become events, summarised at
/// most once per second; what the device says about itself (an error message, a status word
/// flagging a fault) is an event in its own words; a lost link is an event and an error
/// state, and the port is reopened (and the device configured again) with backoff.
class SerialImu final : public StreamingImu {
 public:
  /// A serial IMU as the station file describes it (no I/O until configure()).
  SerialImu(const core::ImuConfig& config, core::Clock& clock, const std::string& where);
  /// Over an injected link (tests): `transport` is used as is and never reopened.
  /// `configurator` may be null (nothing to configure).
  SerialImu(std::string name, std::unique_ptr<ByteTransport> transport,
            std::unique_ptr<FrameDecoder> decoder, double sample_rate_hz,
            std::uint64_t sequence_modulus, core::Clock& clock,
            std::unique_ptr<ImuConfigurator> configurator = nullptr);
  ~SerialImu() override;

  double sample_rate_hz() const override { return sample_rate_hz_; }
  std::uint64_t sequence_modulus() const override { return sequence_modulus_; }
  /// What the device reported in its configuration dialogue; none for a format without one.
  std::optional<UnitIdentity> identity() const override;

 private:
  void on_reader_start() override;
  void open_link(bool after_error) override;
  bool reopen_link() override;
  Result read_step() override;
  void summarise_faults(double now_s, double period_s) override;
  // Runs the configurator on the open link (engine thread at configure(), reader thread at a
  // reopen); throws DeviceConfigError.
  void configure_device();

  std::unique_ptr<ByteTransport> transport_;
  SerialPort* port_ = nullptr;  // transport_ when it is a serial port we may reopen
  std::unique_ptr<FrameDecoder> decoder_;
  std::unique_ptr<ImuConfigurator> configurator_;
  double sample_rate_hz_ = 0.0;
  std::uint64_t sequence_modulus_ = 0;
  mutable std::mutex identity_mutex_;
  std::optional<UnitIdentity> identity_;
  // Reader thread only.
  std::array<std::uint8_t, 4096> chunk_{};
  std::vector<core::ImuSample> decoded_;
  std::map<std::string, std::uint64_t> reported_counters_;
  std::map<std::string, std::uint64_t> device_reports_;  // since the last summary: text, times
};

std::unique_ptr<Imu> make_serial_imu(const core::ImuConfig& config, core::Clock& clock,
                                     const std::string& where);

}  // namespace calstand::drivers
