#include "drivers/sample_clock.hpp"

#include <algorithm>
#include <cmath>

namespace calstand::drivers {

void SampleClock::reset() {
  minima_.clear();
  started_ = false;
  last_stamp_s_ = -1e300;
}

double SampleClock::stamp(double device_time_s, double arrival_s) {
  const double delay = arrival_s - device_time_s;
  if (started_) {
    // A device clock going back or leaping ahead, or samples suddenly arriving much *earlier*
    // than the device clock allows: the device restarted or its time was set, and the old
    // offset means nothing now. A sample arriving much *later* than usual is not a jump: the
    // link stalled (a busy machine, a USB hiccup), and it keeps the estimate.
    const bool clock_jump = device_time_s < last_device_s_ ||
                            device_time_s - last_device_s_ > jump_s_ ||
                            delay < minima_.front().delay_s - jump_s_;
    if (clock_jump) {
      reset();
      ++restarts_;
    }
  }
  started_ = true;
  last_device_s_ = device_time_s;
  // Sliding-window minimum (monotonic deque): drop points that can never be the minimum again
  // and points that left the window.
  while (!minima_.empty() && minima_.back().delay_s >= delay) minima_.pop_back();
  minima_.push_back({device_time_s, delay});
  while (minima_.front().device_s < device_time_s - window_s_) minima_.pop_front();
  const double t = std::max(device_time_s + minima_.front().delay_s, last_stamp_s_);
  last_stamp_s_ = std::min(t, arrival_s);
  return last_stamp_s_;
}

}  // namespace calstand::drivers
