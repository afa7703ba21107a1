#pragma once

#include <chrono>
#include <cstdio>
#include <string>

#include "daemon/run_engine.hpp"

namespace calstand::cli {

/// One-line progress bar on a terminal (stderr): step, phase, label and ETA in station time.
/// Redraws at most every 100 ms of wall time; prints nothing when stderr is not a terminal.
class ProgressBar {
 public:
  ProgressBar();
  void update(const daemon::Progress& p);
  /// Ends the bar's line (call once the run is over).
  void finish();

 private:
  bool enabled_;
  bool drawn_ = false;
  std::chrono::steady_clock::time_point last_draw_{};
};

/// "1:02:03" for seconds (h:mm:ss).
std::string format_duration(double seconds);

}  // namespace calstand::cli
