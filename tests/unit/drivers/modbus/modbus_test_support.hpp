#pragma once

// Shared by the Modbus driver tests: a simulated world advanced on an accelerated clock, a
// child Python process with line I/O, and polling helpers.

#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <functional>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "../child_process.hpp"
#include "core/clock.hpp"
#include "core/station_config.hpp"
#include "sim/sim_world.hpp"

extern char** environ;

namespace calstand::drivers::test {

using namespace std::chrono_literals;

/// A station with a quick chamber and no IMUs (nothing to sample): the chamber follows within
/// seconds of station time, so tests run in well under a second of wall time per step.
inline core::StationConfig quick_chamber_station() {
  auto config = sim::default_station();
  config.imus.clear();
  config.chamber.min_c = -40.0;
  config.chamber.max_c = 120.0;
  config.chamber.max_ramp_c_per_min = 60.0;
  config.chamber.ambient_c = 23.0;
  config.chamber.air_time_constant_s = 2.0;
  config.chamber.control_noise_c = 0.0;
  return config;
}

/// A SimWorld advanced by a background thread to keep up with `clock` (station time), under
/// `mutex`, as `calstand sim-station` does.
class RunningWorld {
 public:
  explicit RunningWorld(const core::StationConfig& config, double time_scale)
      : clock(time_scale), world(config) {
    thread_ = std::thread([this] {
      while (!stop_) {
        {
          std::lock_guard lock(mutex);
          world.advance_to(clock.now_s());
        }
        std::this_thread::sleep_for(2ms);
      }
    });
  }
  ~RunningWorld() {
    stop_ = true;
    thread_.join();
  }
  core::ChamberState chamber() {
    std::lock_guard lock(mutex);
    return world.chamber_state();
  }

  core::SteadyClock clock;
  std::mutex mutex;
  sim::SimWorld world;

 private:
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

/// Polls `condition` every 10 ms until it holds or `timeout` (wall) passes.
inline bool eventually(const std::function<bool()>& condition,
                       std::chrono::milliseconds timeout = 5000ms) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline) {
    if (condition()) return true;
    std::this_thread::sleep_for(10ms);
  }
  return condition();
}

inline std::string script_path(const std::string& name) {
  return std::string(CALSTAND_SOURCE_DIR) + "/tests/unit/drivers/modbus/" + name;
}

/// Why pymodbus cannot be used here, or "" when it can: the system interpreter is needed (the
/// python3 on PATH may be a different one without pymodbus).
inline std::string pymodbus_missing() {
  if (::access(kPython, X_OK) != 0) return std::string(kPython) + " not found";
  ChildProcess probe({kPython, "-c", "import pymodbus; print('ok')"});
  const auto line = probe.read_line(10000ms);
  if (!line || *line != "ok") return std::string("pymodbus is not importable by ") + kPython;
  return {};
}

}  // namespace calstand::drivers::test
