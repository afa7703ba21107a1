#pragma once
// Bias and scale-factor repeatability across power cycles (`calstand analyze repeatability`):
// the spread of a unit's static means, and of its gyro scale factors from turns both ways, from
// one power-up to the next, in datasheet units, with their intervals.

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

/// One gyro axis's scale factor across power-ups, from the rate steps of each cycle that turn
/// about that body axis both ways: (mean at +r - mean at -r) / (2 r) - 1 per cycle and rate,
/// in which every constant part (bias, the Earth rate along the axis) cancels.
struct ScaleRepeatability {
  bool measured = false;          ///< the cycles turn about this axis both ways
  std::vector<double> rates_dps;  ///< rate magnitudes turned
  /// Per cycle, the scale error at the first rate less its mean over the cycles [ppm].
  std::vector<double> scale_ppm;
  double spread_ppm = 0.0;  ///< standard deviation over cycles (pooled over rates)
  /// The white noise of one cycle's estimate, from the noise of the cycle's static capture
  /// scaled to the turns' sample counts [ppm].
  double noise_of_estimates_ppm = 0.0;
  /// sqrt(spread^2 - noise^2), 1 sigma, and its chi-square interval [ppm].
  double repeatability_ppm = 0.0;
  double repeatability_lo_ppm = 0.0;
  double repeatability_hi_ppm = 0.0;
  int dof = 0;  ///< of the spread: rates x (cycles - 1)
};

struct RepeatabilityAnalysis {
  std::int64_t run = 0;
  std::string device;
  std::size_t cycles = 0;
  std::size_t positions = 0;  ///< static captures per cycle
  int dof = 0;                ///< degrees of freedom of the spread
  double confidence = 0.95;
  std::array<ChannelRepeatability, 6> channels;
  std::array<ScaleRepeatability, 3> gyro_scale;  ///< body x, y, z
};

/// Groups the completed captures and rate steps of `run` by their `cycle` loop value (a
/// for_each over power cycles: library procedure `repeatability`), compares the k-th capture of
/// every cycle, and the scale factor of every turn pair (+r and -r about one body axis, found
/// from the encoders and the station geometry). Throws core::InputError naming the run when it
/// has fewer than two cycles with captures, cycles with different numbers of captures, or a
/// cycle that lacks a turn pair the others have.
RepeatabilityAnalysis analyse_repeatability(store::Database& db, std::int64_t run,
                                            const std::string& device);

/// `{"run", "device", "cycles", "positions", "dof", "confidence",
///   "gyro": {"bias_repeatability_deg_per_h": [x,y,z], "interval_deg_per_h": [[lo,hi] x3],
///            "spread_deg_per_h": [...], "noise_of_means_deg_per_h": [...],
///            "turn_on_bias_deg_per_h": [[per cycle] x3]},
///            "scale_factor_repeatability_ppm": [x,y,z], "scale_interval_ppm": [[lo,hi] x3],
///            "scale_spread_ppm": [...], "scale_noise_ppm": [...], "scale_per_cycle_ppm":
///            [[per cycle] x3], "scale_rates_dps": [[...] x3], "scale_dof": [...]} (scale
///            entries null about an axis the cycles do not turn about),
///   "accel": the bias entries in ug ("bias_repeatability_ug", ...)}`
nlohmann::json to_json(const RepeatabilityAnalysis& r);

}  // namespace calstand::analysis
