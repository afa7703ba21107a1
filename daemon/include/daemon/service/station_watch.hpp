#pragma once

#include <chrono>
#include <memory>
#include <optional>
#include <vector>

#include "core/chamber_state.hpp"
#include "core/station_config.hpp"
#include "core/table_state.hpp"
#include "daemon/service/live_status.hpp"
#include "drivers/station.hpp"

namespace calstand::daemon::service {

/// Every device of `config` as "offline" (no link open).
std::vector<DeviceStatus> offline_devices(const core::StationConfig& config);

/// Every device of `station` with its lifecycle state and fault counters.
std::vector<DeviceStatus> read_devices(drivers::Station& station);

/// The table and the chamber between runs. A run opens the station's devices for itself; in
/// between, the daemon keeps the table and the chamber open for reading only (configured,
/// which sends the table its axis limits, never activated: no move, rate or setpoint), so `GET
/// /station` and the live stream show where the table stands and what the chamber air does while
/// the station waits, and a link that broke overnight shows before the next run. The IMUs stay
/// closed (their streams are only read during a run) and show "offline".
///
/// Used from one thread (the daemon's run thread).
class IdleStationWatch {
 public:
  explicit IdleStationWatch(core::StationConfig config) : config_(std::move(config)) {}

  struct Reading {
    std::vector<DeviceStatus> devices;
    std::optional<core::TableState> table;      ///< none when the table's link is not up
    std::optional<core::ChamberState> chamber;  ///< none when the chamber's link is not up
  };

  /// Opens the links when they are not (again at most every `retry` after a failure) and reads
  /// both devices.
  Reading read();
  /// Closes the links: before a run (or a hold) opens the devices for itself.
  void release() { station_.reset(); }
  /// The operator's close of latched table interlocks (Turntable::close_interlocks()), over the
  /// links this watch holds (opened now when they are not up).
  drivers::InterlockClosure close_interlocks();

  /// How long after a failed open the links are tried again.
  static constexpr std::chrono::seconds kRetry{30};

 private:
  core::StationConfig config_;
  std::unique_ptr<drivers::Station> station_;
  std::chrono::steady_clock::time_point next_open_{};
};

}  // namespace calstand::daemon::service
