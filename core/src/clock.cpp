#include "core/clock.hpp"

#include <thread>

namespace calstand::core {

SteadyClock::SteadyClock(double time_scale, double start_s)
    : epoch_(std::chrono::steady_clock::now()),
      time_scale_(time_scale > 0.0 ? time_scale : 1.0),
      start_s_(start_s) {}

double SteadyClock::now_s() const {
  return start_s_ +
         time_scale_ *
             std::chrono::duration<double>(std::chrono::steady_clock::now() - epoch_).count();
}

void SteadyClock::sleep_until(double t_s) {
  const auto deadline = epoch_ + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                     std::chrono::duration<double>((t_s - start_s_) / time_scale_));
  std::this_thread::sleep_until(deadline);
}

double VirtualClock::now_s() const {
  std::lock_guard lock(mutex_);
  return now_s_;
}

void VirtualClock::sleep_until(double /*t_s*/) {
  // Virtual time belongs to the simulator loop: a waiter cannot move it.
}

void VirtualClock::advance(double dt_s) {
  if (dt_s <= 0.0) return;
  std::lock_guard lock(mutex_);
  now_s_ += dt_s;
}

void VirtualClock::advance_to(double t_s) {
  std::lock_guard lock(mutex_);
  if (t_s > now_s_) now_s_ = t_s;
}

}  // namespace calstand::core
