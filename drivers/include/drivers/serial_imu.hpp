#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "core/clock.hpp"
#include "core/station_config.hpp"
#include "drivers/device_support.hpp"
#include "drivers/imu.hpp"
#include "drivers/imu_frame.hpp"
#include "drivers/sample_clock.hpp"
#include "drivers/serial_port.hpp"

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
/// `calstand sim-station`). A reader thread, running while the device is active, decodes
/// frames, stamps each sample on the station clock (SampleClock) and buffers it for poll().
/// Decoder faults (CRC and length errors, garbage) become events, summarised at most once per
/// second; a lost link is an event and an error state, and the port is reopened with backoff.
class SerialImu final : public Imu {
 public:
  /// A serial IMU as the station file describes it (no I/O until configure()).
  SerialImu(const core::ImuConfig& config, core::Clock& clock, const std::string& where);
  /// Over an injected link (tests): `transport` is used as is and never reopened.
  SerialImu(std::string name, std::unique_ptr<ByteTransport> transport,
            std::unique_ptr<FrameDecoder> decoder, double sample_rate_hz,
            std::uint64_t sequence_modulus, core::Clock& clock);
  ~SerialImu() override;

  const std::string& name() const override { return name_; }
  Result configure() override;
  Result activate() override;
  Result deactivate() override;
  DeviceState state() const override { return life_.state(); }
  std::map<std::string, std::uint64_t> fault_counters() const override;
  std::vector<DeviceEvent> take_events() override { return events_.take(); }

  std::vector<core::ImuSample> poll() override;
  double sample_rate_hz() const override { return sample_rate_hz_; }
  std::uint64_t sequence_modulus() const override { return sequence_modulus_; }

 private:
  void read_loop();
  void report_decoder_faults(double now_s, bool force);
  bool reopen();
  void stop_reader();

  std::string name_;
  core::Clock& clock_;
  std::unique_ptr<ByteTransport> transport_;
  SerialPort* port_ = nullptr;  // transport_ when it is a serial port we may reopen
  std::unique_ptr<FrameDecoder> decoder_;
  double sample_rate_hz_;
  std::uint64_t sequence_modulus_;
  Lifecycle life_;
  FaultCounters faults_{"read_errors", "reopens", "buffer_overflows"};
  EventQueue events_;

  std::thread reader_;
  std::atomic<bool> running_{false};
  mutable std::mutex mutex_;  // guards buffer_ and decoder_counters_
  std::vector<core::ImuSample> buffer_;
  std::map<std::string, std::uint64_t> decoder_counters_;
  // Reader thread only.
  SampleClock sample_clock_;
  std::map<std::string, std::uint64_t> reported_counters_;
  double last_report_s_ = 0.0;
};

std::unique_ptr<Imu> make_serial_imu(const core::ImuConfig& config, core::Clock& clock,
                                     const std::string& where);

}  // namespace calstand::drivers
