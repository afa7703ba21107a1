#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/clock.hpp"
#include "core/station_config.hpp"
#include "drivers/can_sample_assembler.hpp"
#include "drivers/can_signal_map.hpp"
#include "drivers/can_transport.hpp"
#include "drivers/streaming_imu.hpp"

namespace calstand::drivers {

/// `connection` of an IMU with backend "socketcan" (docs/protocols.md, "IMU over CAN"):
///   {"interface": "can0", "map": {...} | "map_file": "calstand-imu-can.json",
///    "sample_rate_hz": 200, "sequence_modulus": 256, "filter_ids": true,
///    "kernel_timestamps": true}
struct CanImuConnection {
  std::string interface;  ///< SocketCAN interface name ("can0", "vcan0")
  CanSignalMap map;
  double sample_rate_hz = 0.0;         ///< the device's nominal output rate [Hz]
  std::uint64_t sequence_modulus = 0;  ///< counter wraps to 0 here; default 2^sequence bits
  /// Receive only the map's ids (kernel filter). false shows every id on the bus, counted as
  /// unknown_ids: for commissioning, to see whether the IMU sends ids the map lacks.
  bool filter_ids = true;
  /// Take arrival times from the kernel's receive stamp rather than the reader's wake-up.
  bool kernel_timestamps = true;

  /// Parses and validates (reads map_file, no device I/O). Throws core::InputError naming
  /// `where`.field (e.g. "imus[0].connection.map.signals.gyro_x.length_bits"). The station
  /// loader has already made map_file absolute (core::StationConfig resolves "*_file" fields);
  /// a relative one left is resolved against `base_dir` when given, else used as is.
  static CanImuConnection from_json(const nlohmann::json& connection, const std::string& where,
                                    const std::string& base_dir = {});
};

/// An IMU sending its samples as CAN frames described by a signal map. The reader
/// (StreamingImu) reads frames, reassembles samples (CanSampleAssembler), stamps each on the
/// station clock (SampleClock, from the kernel's receive time when there is one) and buffers
/// it for poll(). Faults are counted and summarised in at most one event per second of station
/// time; a lost link is an event and the error state, and the transport is reopened with
/// backoff while active (a socket pair cannot be, and stays in error).
/// No sample is ever invented: missing frames mean a missing sample and a sequence gap.
/// configure() opens the transport and sets its filters (from kError: closes and reopens it
/// first). fault_counters() adds malformed_messages, clock_restarts and the assembler's
/// counters (CanAssemblyCounters).
class CanImu final : public StreamingImu {
 public:
  /// As the station file describes it (no I/O until configure()).
  CanImu(const core::ImuConfig& config, core::Clock& clock, const std::string& where,
         const std::string& base_dir = {});
  /// Over an injected transport (tests, simulators); connection.interface is not used.
  CanImu(std::string name, CanImuConnection connection, std::unique_ptr<CanTransport> transport,
         core::Clock& clock);
  ~CanImu() override;

  /// Starts the reader. Refused when unconfigured or in kError (configure() again first).
  Result activate() override;

  double sample_rate_hz() const override { return connection_.sample_rate_hz; }
  std::uint64_t sequence_modulus() const override { return connection_.sequence_modulus; }

 private:
  void open_link(bool after_error) override;
  bool reopen_link() override;
  Result read_step() override;
  void summarise_faults(double now_s, double period_s) override;
  void on_reader_start() override { last_arrival_s_ = -1e300; }
  double arrival_time_s(const ReceivedCanFrame& frame) const;
  void open_transport();

  CanImuConnection connection_;
  std::unique_ptr<CanTransport> transport_;
  // Reader thread only (or while it is stopped).
  CanSampleAssembler assembler_;
  std::vector<core::ImuSample> decoded_;
  std::map<std::string, std::uint64_t> reported_;
  double last_arrival_s_ = -1e300;  // station clock [s]
};

/// The CAN IMU of `config` (backend "socketcan"); `where` names its config ("imus[0].connection").
std::unique_ptr<Imu> make_can_imu(const core::ImuConfig& config, core::Clock& clock,
                                  std::string where, const std::string& base_dir = {});

}  // namespace calstand::drivers
