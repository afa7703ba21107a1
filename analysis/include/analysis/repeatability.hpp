#pragma once
// Bias repeatability across power cycles (`calstand analyze repeatability`): the spread of a
// unit's static means from one power-up to the next, in datasheet units, with its interval.

#include <array>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "store/database.hpp"

namespace calstand::analysis {

/// One channel: gx gy gz in deg/h, ax ay az in ug.
struct ChannelRepeatability {
  std::string channel;
  /// Per cycle, the static mean less the mean over the cycles (the part that changes between
  /// power-ups; for several positions per cycle, the first position's).
  std::vector<double> turn_on_bias;
  double spread = 0.0;          ///< standard deviation of the cycle means (pooled over positions)
  double noise_of_means = 0.0;  ///< the measurement noise of one capture's mean, from inside it
  /// sqrt(spread^2 - noise_of_means^2): the turn-on bias repeatability (1 sigma), and its
  /// interval from the chi-square distribution of the spread.
  double repeatability = 0.0;
  double repeatability_lo = 0.0;
  double repeatability_hi = 0.0;
};

struct RepeatabilityAnalysis {
  std::int64_t run = 0;
  std::string device;
  std::size_t cycles = 0;
  std::size_t positions = 0;  ///< static captures per cycle
  int dof = 0;                ///< degrees of freedom of the spread
  double confidence = 0.95;
  std::array<ChannelRepeatability, 6> channels;
};

/// Groups the completed captures of `run` by their `cycle` loop value (a for_each over power
/// cycles: library procedure `repeatability`) and compares the k-th capture of every cycle.
/// Throws core::InputError naming the run when it has fewer than two cycles with captures, or
/// cycles with different numbers of captures.
RepeatabilityAnalysis analyse_repeatability(store::Database& db, std::int64_t run,
                                            const std::string& device);

/// `{"run", "device", "cycles", "positions", "dof", "confidence",
///   "gyro": {"bias_repeatability_deg_per_h": [x,y,z], "interval_deg_per_h": [[lo,hi] x3],
///            "spread_deg_per_h": [...], "noise_of_means_deg_per_h": [...],
///            "turn_on_bias_deg_per_h": [[per cycle] x3]},
///   "accel": the same in ug ("bias_repeatability_ug", ...)}`
nlohmann::json to_json(const RepeatabilityAnalysis& r);

}  // namespace calstand::analysis
