#pragma once
// The power-on (warm-up) test (`calstand analyze warmup`): how a unit's bias settles after it is
// switched on. Each axis's static output from power-up is fitted as its settled value, an
// exponential transient and, where the unit warms itself, its temperature's share:
//   y(t) = c + A exp(-t / tau) + k (T(t) - T_end),
// so that self-heating (a thermal sensitivity, calibrated elsewhere) is not taken for the
// power-on transient.

#include <array>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "store/database.hpp"

namespace calstand::analysis {

/// One channel: gx gy gz in deg/h, ax ay az in ug.
struct ChannelWarmup {
  std::string channel;
  double amplitude = 0.0;  ///< A: the bias at power-up less its settled value
  double amplitude_sigma = 0.0;
  double time_constant_s = 0.0;  ///< tau
  double settled = 0.0;          ///< c: the settled output (gravity and Earth rate included)
  /// From power-up until |A| exp(-t / tau) stays within the band [s]; 0 when it starts inside.
  double time_to_band_s = 0.0;
  /// |A| > 3 sigma and tau inside the record (more than two bins, less than a third of it):
  /// otherwise there is no transient to speak of, and tau means nothing.
  bool resolved = false;
  /// The unit's temperature is a term of this channel's fit: it explained far more than noise
  /// (an F-test at 1e-6; the record's bias wander makes nominal levels optimistic).
  bool temperature_term = false;
};

struct WarmupAnalysis {
  std::int64_t run = 0;
  std::string device;
  std::size_t step = 0;
  std::string step_label;
  double duration_s = 0.0;
  double bin_s = 0.0;               ///< the fit works on means over bins this long
  double temperature_rise_c = 0.0;  ///< of the IMU over the capture (self-heating)
  /// The IMU's temperature changed enough to be tried as a term (each channel keeps it only
  /// when it explains far more than noise: ChannelWarmup::temperature_term).
  bool with_temperature = false;
  double band_deg_per_h = 0.0;
  double band_ug = 0.0;
  std::array<ChannelWarmup, 6> channels;
};

/// Fits the warm-up of `device` in `run` from capture `step` (none: the first capture after a
/// power-on step), time from its first sample. Bands: how close to the settled value counts as
/// settled [deg/h, ug]. Throws core::InputError naming the run or step when there is no such
/// capture or it is too short (under 60 s).
WarmupAnalysis analyse_warmup(store::Database& db, std::int64_t run, const std::string& device,
                              std::optional<std::size_t> step, double band_deg_per_h,
                              double band_ug);

/// `{"run", "device", "step", "step_label", "duration_s", "bin_s", "temperature_rise_c",
///   "with_temperature", "band": {"deg_per_h", "ug"},
///   "gyro": {"amplitude_deg_per_h": [x,y,z], "amplitude_sigma_deg_per_h": [...],
///            "time_constant_s": [...], "time_to_band_s": [...], "resolved": [...],
///            "temperature_term": [...]},
///   "accel": the same in ug}`
nlohmann::json to_json(const WarmupAnalysis& w);

}  // namespace calstand::analysis
