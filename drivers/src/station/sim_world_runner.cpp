#include "drivers/sim_world_runner.hpp"

#include <algorithm>
#include <chrono>

namespace calstand::drivers {
namespace {
// Wall time between world advances [ms]: short enough that protocol replies see fresh state.
constexpr auto kSlice = std::chrono::milliseconds(1);
// At most this much wall-clock-equivalent world time per advance [s] (times the time scale),
// so the mutex is never held for long even when the world has fallen behind, yet the world
// catches up after a stall whatever the scale.
constexpr double kMaxAdvanceWallS = 0.05;
}  // namespace

SimWorldRunner::SimWorldRunner(const core::StationConfig& config, double time_scale)
    : world_(config), time_scale_(time_scale > 0.0 ? time_scale : 1.0) {}

SimWorldRunner::~SimWorldRunner() { stop(); }

void SimWorldRunner::start() {
  if (running_.exchange(true)) return;
  {
    std::lock_guard lock(mutex_);
    world0_s_ = world_.now_s();
  }
  wall0_ = std::chrono::steady_clock::now();
  started_ = true;
  thread_ = std::thread([this] { loop(); });
}

double SimWorldRunner::clock_s() const {
  if (!started_) return world0_s_;
  const double wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0_).count();
  return world0_s_ + time_scale_ * wall_s;
}

void SimWorldRunner::stop() {
  running_ = false;
  if (thread_.joinable()) thread_.join();
}

void SimWorldRunner::loop() {
  while (running_) {
    const double target = clock_s();
    {
      std::lock_guard lock(mutex_);
      world_.advance_to(std::min(target, world_.now_s() + kMaxAdvanceWallS * time_scale_));
      lag_s_ = target - world_.now_s();
    }
    std::this_thread::sleep_for(kSlice);
  }
}

}  // namespace calstand::drivers
