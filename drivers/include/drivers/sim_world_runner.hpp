#pragma once

#include <atomic>
#include <chrono>
#include <functional>
#include <mutex>
#include <thread>

#include "core/station_config.hpp"
#include "sim/sim_world.hpp"

namespace calstand::drivers {

/// Runs a simulated world in real time, `time_scale` times faster than the wall clock, on its
/// own thread, for the protocol simulators (`calstand sim-station`). Everything that touches the
/// world (the protocol servers, the IMU streamers through the sample sink) holds mutex();
/// the world advances in small slices so that nobody waits long for it.
class SimWorldRunner {
 public:
  /// The world of `config` (every backend "sim"), not yet running.
  SimWorldRunner(const core::StationConfig& config, double time_scale);
  ~SimWorldRunner();
  SimWorldRunner(const SimWorldRunner&) = delete;
  SimWorldRunner& operator=(const SimWorldRunner&) = delete;

  void start();
  void stop();

  sim::SimWorld& world() { return world_; }
  std::mutex& mutex() { return mutex_; }
  double time_scale() const { return time_scale_; }
  /// How far the world lags behind where the wall clock says it should be [s of world time]:
  /// near 0 while the CPU keeps up with the time scale.
  double lag_s() const { return lag_s_.load(); }
  /// The world time the wall clock stands at now [s]: where the world is heading. The world
  /// itself advances in slices (a millisecond of wall time, 20 ms of world time at 20x); a
  /// protocol reply that reads a moving axis extrapolates to this, as a controller reading its
  /// encoder now would. The world's own time before start().
  double clock_s() const;

 private:
  void loop();

  sim::SimWorld world_;
  std::mutex mutex_;
  double time_scale_;
  std::thread thread_;
  std::atomic<bool> running_{false};
  std::atomic<double> lag_s_{0.0};
  // Set by start() before the thread runs; read by clock_s() from any thread.
  std::atomic<bool> started_{false};
  std::chrono::steady_clock::time_point wall0_;
  double world0_s_ = 0.0;
};

}  // namespace calstand::drivers
