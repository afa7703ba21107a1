#pragma once

#include <string>

namespace calstand::store {

/// The wall clock now as UTC ISO-8601 with milliseconds, e.g. `2024-05-01T12:34:56.789Z`.
std::string utc_now_iso8601();

/// A moment as the store records it: station clock and wall clock.
struct Stamp {
  double clock_s = 0.0;  ///< station clock (core::Clock::now_s()) [s]
  std::string utc;       ///< UTC ISO-8601 wall time

  /// The station time `clock_s` stamped with the wall clock now.
  static Stamp now(double clock_s) { return {clock_s, utc_now_iso8601()}; }
};

}  // namespace calstand::store
