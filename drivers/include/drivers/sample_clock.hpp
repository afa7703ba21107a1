#pragma once

#include <deque>

namespace calstand::drivers {

/// Puts an IMU's samples on the station clock. A real link delivers samples in bursts (UART
/// FIFOs, USB frames, scheduling, an accelerated simulator), so the arrival time says little
/// about when a sample was taken; the device's own clock says it well but has another epoch.
/// The station time of a sample is its device time plus an offset: the smallest
/// (arrival - device time) seen over the last `window_s` of device time, i.e. the sample that
/// waited least in buffers. The window lets the offset follow the slow drift between the two
/// clocks. A device clock that jumps (restart, wrap, time set) restarts the estimate.
/// Not thread safe: one per stream, used from the stream's reader.
class SampleClock {
 public:
  /// The estimate's memory and the device clock leap that restarts it, in wall seconds: long
  /// beside a link's bursts and a reader's scheduling hold-ups.
  static constexpr double kWindowWallS = 10.0;
  static constexpr double kJumpWallS = 5.0;

  /// Arrivals must be given in the order they happened.
  explicit SampleClock(double window_s = kWindowWallS, double jump_s = kJumpWallS)
      : window_s_(window_s), jump_s_(jump_s) {}
  /// The clock for a station whose clock runs `time_scale` times faster than the wall (a
  /// rehearsal against `calstand sim-station --time-scale K`): the window and the jump limit
  /// are kept in wall seconds. They guard against link and scheduling delays, which do not
  /// speed up with the station: at K = 20 a window of 10 station seconds is half a second of
  /// wall time, and a reader held up for longer than that (a busy machine) took its own delay
  /// for the link's, stamping whole captures seconds late.
  static SampleClock for_time_scale(double time_scale) {
    const double k = time_scale > 0.0 ? time_scale : 1.0;
    return SampleClock(kWindowWallS * k, kJumpWallS * k);
  }

  /// Station time [s] of the sample taken at `device_time_s` and received at `arrival_s`
  /// (station clock). Never later than `arrival_s`; never earlier than the previous result.
  double stamp(double device_time_s, double arrival_s);
  /// Forgets the estimate (the next sample starts a new one).
  void reset();
  /// Restarts counted since construction (device clock jumps).
  unsigned long restarts() const { return restarts_; }

 private:
  struct Point {
    double device_s;
    double delay_s;  // arrival - device time
  };
  double window_s_;
  double jump_s_;
  std::deque<Point> minima_;  // increasing delay_s; front is the window's minimum
  double last_device_s_ = 0.0;
  double last_stamp_s_ = -1e300;
  bool started_ = false;
  unsigned long restarts_ = 0;
};

}  // namespace calstand::drivers
