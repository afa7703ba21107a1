#pragma once

#include <cstdint>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "core/chamber_state.hpp"
#include "core/table_state.hpp"
#include "daemon/run_engine.hpp"

namespace calstand::daemon::service {

/// A device as `GET /station` shows it.
struct DeviceStatus {
  std::string kind;  ///< "table", "chamber" or "imu"
  std::string name;
  std::string backend;  ///< e.g. "sim", "modbus"
  std::string state;    ///< lifecycle state ("active", ...); "offline" between runs
  std::map<std::string, std::uint64_t> fault_counters;  ///< since the run's station came up
};

/// What the station is doing now: written by the run thread, read by API threads.
struct LiveSnapshot {
  std::optional<std::int64_t> run;   ///< the run on the station (none when idle)
  std::optional<std::int64_t> held;  ///< an interrupted run waiting for resume or abort
  /// Why the next run (queued, or interrupted and due to resume) cannot start now: the disk
  /// full, a table interlock latched. It waits and starts by itself once the cause is gone.
  std::optional<std::string> waiting;
  Progress progress;  ///< of `run`
  std::vector<DeviceStatus> devices;
  std::optional<core::TableState> table;
  std::optional<core::ChamberState> chamber;
};

/// The latest LiveSnapshot, guarded by a mutex (copies in and out; all methods thread safe).
class LiveStatus {
 public:
  LiveSnapshot snapshot() const {
    std::lock_guard lock(mutex_);
    return snapshot_;
  }
  template <class F>
  void update(F&& change) {
    std::lock_guard lock(mutex_);
    change(snapshot_);
  }

 private:
  mutable std::mutex mutex_;
  LiveSnapshot snapshot_;
};

}  // namespace calstand::daemon::service
