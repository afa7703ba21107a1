#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/clock.hpp"
#include "core/station_config.hpp"
#include "drivers/imu_frame.hpp"
#include "drivers/serial_port.hpp"
#include "drivers/streaming_imu.hpp"

namespace calstand::drivers {

/// `connection` of an IMU with backend "serial" (docs/stations.md):
///   {"path": "/dev/ttyUSB0", "baud": 921600, "parity": "none", "format": "calstand",
///    "sample_rate_hz": 400, "sequence_modulus": 4294967296}
struct SerialImuConnection {
  SerialOptions serial;
  std::string format = "calstand";  ///< frame format; "calstand" (docs/protocols.md) for now
  double sample_rate_hz = 0.0;      ///< the device's nominal output rate [Hz]
  std::uint64_t sequence_modulus = std::uint64_t{1} << 32;  ///< counter wraps to 0 here

  /// Throws core::InputError naming `where`.field (e.g. "imus[0].connection.baud").
  static SerialImuConnection from_json(const nlohmann::json& connection, const std::string& where);
};

/// The frame decoder of `format` ("calstand"); throws core::InputError naming `where` otherwise.
std::unique_ptr<FrameDecoder> make_frame_decoder(const std::string& format,
                                                 std::uint64_t sequence_modulus,
                                                 const std::string& where);

/// An IMU streaming frames over a byte link (a serial line in the lab; a pseudo-terminal from
/// `calstand sim-station`). The reader (StreamingImu) decodes frames, stamps each sample on the
/// station clock and buffers it for poll(). Decoder faults (CRC and length errors, garbage)
/// become events, summarised at most once per second; a lost link is an event and an error
/// state, and the port is reopened with backoff.
class SerialImu final : public StreamingImu {
 public:
  /// A serial IMU as the station file describes it (no I/O until configure()).
  SerialImu(const core::ImuConfig& config, core::Clock& clock, const std::string& where);
  /// Over an injected link (tests): `transport` is used as is and never reopened.
  SerialImu(std::string name, std::unique_ptr<ByteTransport> transport,
            std::unique_ptr<FrameDecoder> decoder, double sample_rate_hz,
            std::uint64_t sequence_modulus, core::Clock& clock);
  ~SerialImu() override;

  double sample_rate_hz() const override { return sample_rate_hz_; }
  std::uint64_t sequence_modulus() const override { return sequence_modulus_; }

 private:
  void on_reader_start() override;
  void open_link(bool after_error) override;
  bool reopen_link() override;
  Result read_step() override;
  void summarise_faults(double now_s, double period_s) override;

  std::unique_ptr<ByteTransport> transport_;
  SerialPort* port_ = nullptr;  // transport_ when it is a serial port we may reopen
  std::unique_ptr<FrameDecoder> decoder_;
  double sample_rate_hz_ = 0.0;
  std::uint64_t sequence_modulus_ = 0;
  // Reader thread only.
  std::array<std::uint8_t, 4096> chunk_{};
  std::vector<core::ImuSample> decoded_;
  std::map<std::string, std::uint64_t> reported_counters_;
};

std::unique_ptr<Imu> make_serial_imu(const core::ImuConfig& config, core::Clock& clock,
                                     const std::string& where);

}  // namespace calstand::drivers
