#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <vector>

#include "core/imu_sample.hpp"

/// Static intervals of a recording without step labels (an IMU turned by hand between poses),
/// as imu_tk finds them (Tedaldi, Pretto, Menegatti, ICRA 2014): the variance of the
/// accelerometer in a sliding window, against a threshold scaled to the initial rest.
///
/// - Statistic: v(t) = sum over the three accel axes of the sample variance in the window of
///   `window_s` centred on t [(m/s^2)^2]. Time stamps are the samples' own (receive_time_s).
/// - Initial rest: the recording must start at rest (imu_tk needs about 50 s for the gyro
///   bias). Its end is given (`initial_rest_s`) or found: the median v over the first
///   `rest_probe_s` is the quiet level (refused when v varies by more than `rest_end_factor`
///   within the probe: the recording starts in motion), and the rest ends where v first
///   exceeds `rest_end_factor` times it. The rest level rho is the mean v over the windows that lie
///   wholly inside the rest.
/// - Threshold (`rule`):
///   kRestQuantile (default): the rest's own distribution decides. Over the rest, v / rho is
///     modelled as chi-square over its degrees of freedom nu, with nu measured from the rest
///     itself (nu = 2 rho^2 / var(v)): correlated or quantized noise shows as fewer degrees of
///     freedom than the window's samples. The multiple k is the (1 - `false_alarm`) quantile of
///     that distribution (a window of pure rest noise crosses it once in 1/false_alarm
///     windows), but at least `min_multiple` (3): a pose held by hand or on a softer surface is
///     a little less quiet than the bench rest and must still count, and a turn raises v by
///     orders of magnitude, so the margin costs nothing. Why not the calibration residual (as
///     imu_tk): that needs a fit per candidate; it is offered by gravity_norm.hpp
///     (detect_and_calibrate_accel), which tries a list of multiples and keeps the one with the
///     smallest |f|-g residual.
///   kMultiple: k = `threshold_multiple` times rho (imu_tk's form).
///   kAbsolute: `absolute_threshold` [(m/s^2)^2].
/// - A sample is static when v < threshold; runs of static samples lasting `min_duration_s` or
///   more are the intervals (a centred window keeps each interval about half a window away
///   from the motion on either side). The first interval, when it starts within a window of
///   the first sample, is the initial rest.
/// Pure function, thread safe.
namespace calstand::solver {

enum class ThresholdRule { kRestQuantile, kMultiple, kAbsolute };

struct StaticDetectorOptions {
  double window_s = 1.0;          ///< variance window (imu_tk: 101 samples at 100 Hz)
  double min_duration_s = 1.0;    ///< shortest interval kept
  double initial_rest_s = 0.0;    ///< duration of the initial rest; 0: found from the data
  double rest_probe_s = 2.0;      ///< the quiet level is taken over this much of the start
  double rest_end_factor = 10.0;  ///< the rest ends where v exceeds this times the quiet level
  ThresholdRule rule = ThresholdRule::kRestQuantile;
  double false_alarm = 1e-6;        ///< kRestQuantile: tail probability per window
  double min_multiple = 3.0;        ///< kRestQuantile: lower bound of the multiple
  double threshold_multiple = 0.0;  ///< kMultiple
  double absolute_threshold = 0.0;  ///< kAbsolute [(m/s^2)^2]
};

struct StaticInterval {
  std::size_t begin = 0;  ///< first sample index
  std::size_t end = 0;    ///< one past the last
  double start_s = 0.0;   ///< time of the first sample
  double end_s = 0.0;     ///< time of the last sample
  bool initial_rest = false;
  Eigen::Vector3d mean_accel_mps2 = Eigen::Vector3d::Zero();
  Eigen::Vector3d mean_gyro_dps = Eigen::Vector3d::Zero();
  double mean_statistic = 0.0;  ///< mean v over the interval [(m/s^2)^2]
  double duration_s() const { return end_s - start_s; }
};

struct StaticDetection {
  std::vector<StaticInterval> intervals;  ///< in time order; [0] is the rest when there is one
  bool has_initial_rest = false;
  // The initial rest as used for the threshold.
  double rest_start_s = 0.0;
  double rest_end_s = 0.0;
  bool rest_from_data = false;      ///< found from the data (not given)
  double rest_level_mps2_sq = 0.0;  ///< rho: mean v over the rest
  double rest_effective_dof = 0.0;  ///< nu of the rest statistic
  double threshold_mps2_sq = 0.0;   ///< the threshold on v
  double threshold_multiple = 0.0;  ///< threshold / rho
  ThresholdRule rule = ThresholdRule::kRestQuantile;
  std::string rule_text;           ///< the threshold's reason in words
  std::size_t rejected_short = 0;  ///< static runs shorter than min_duration_s
  double window_s = 0.0;
  double min_duration_s = 0.0;
};

/// Throws core::InputError (where "static detector") when there are fewer than three windows
/// of samples, time stamps that do not increase, non-finite options, or when the recording
/// does not start at rest (no quiet start to scale the threshold to).
StaticDetection detect_static_intervals(std::span<const core::ImuSample> samples,
                                        const StaticDetectorOptions& options);

/// The windowed statistic v of every sample [(m/s^2)^2] (for plots and checks).
std::vector<double> windowed_accel_variance(std::span<const core::ImuSample> samples,
                                            double window_s);

/// {"window_s", "min_duration_s", "rule", "rule_text", "threshold_mps2_sq",
///  "threshold_multiple", "rest": {"start_s", "end_s", "from_data", "level_mps2_sq",
///  "effective_dof"} | null, "rejected_short", "intervals": [{"index", "begin", "end",
///  "start_s", "end_s", "duration_s", "initial_rest", "mean_accel_mps2": [x, y, z],
///  "mean_gyro_dps": [x, y, z], "statistic_mps2_sq"}]}
nlohmann::json static_detection_to_json(const StaticDetection& d);

}  // namespace calstand::solver
