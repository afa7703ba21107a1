#pragma once

#include <chrono>
#include <mutex>

namespace calstand::core {

/// Station time [s] behind one interface, so the same engine code runs on real hardware and on
/// the simulator's virtual time (hours of lab time in seconds).
class Clock {
 public:
  virtual ~Clock() = default;
  /// Seconds since this clock's epoch; monotonic, never decreasing.
  virtual double now_s() const = 0;
  /// Blocks (real clock) or returns at once (virtual clock) until now_s() >= t_s; a virtual
  /// clock is moved only by its owner, so waiting on it never advances it.
  virtual void sleep_until(double t_s) = 0;
  /// True when time only moves when the simulator advances it.
  virtual bool is_virtual() const = 0;
  /// Station seconds per wall second: limits that guard against link and scheduling delays
  /// are kept in wall seconds with it. 1 unless a clock runs faster than the wall.
  virtual double time_scale() const { return 1.0; }
};

/// std::chrono::steady_clock, epoch at construction. Thread safe. `time_scale` station seconds
/// pass per real second: 1 in a lab; more when rehearsing against an accelerated simulator
/// (`calstand sim-station --time-scale K`). Reads `start_s` at construction (a run resumed
/// after a restart continues its station time).
class SteadyClock final : public Clock {
 public:
  explicit SteadyClock(double time_scale = 1.0, double start_s = 0.0);
  double now_s() const override;
  double time_scale() const override { return time_scale_; }
  void sleep_until(double t_s) override;
  bool is_virtual() const override { return false; }

 private:
  std::chrono::steady_clock::time_point epoch_;
  double time_scale_;
  double start_s_;
};

/// Time advanced explicitly by the simulator. Thread safe.
class VirtualClock final : public Clock {
 public:
  explicit VirtualClock(double start_s = 0.0) : now_s_(start_s) {}
  double now_s() const override;
  void sleep_until(double t_s) override;
  bool is_virtual() const override { return true; }

  /// Moves time forward by dt_s >= 0 (negative values are ignored: time never goes back).
  void advance(double dt_s);
  /// Moves time to t_s if it is later than now.
  void advance_to(double t_s);

 private:
  mutable std::mutex mutex_;
  double now_s_;
};

}  // namespace calstand::core
