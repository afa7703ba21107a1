#pragma once
// The output dynamics of a unit's gyros from an oscillation test (`calstand analyze bandwidth`):
// gain and phase of each gyro against the table encoder at each frequency, the -3 dB bandwidth
// and the output delay, as a datasheet states them.

#include <array>
#include <cstddef>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "store/database.hpp"

namespace calstand::analysis {

/// One oscillation step: the gyro along the oscillating table axis against the encoder rate.
struct BandwidthPoint {
  std::size_t step = 0;
  std::string label;
  int axis = 0;  ///< body axis along the oscillating table axis: 0, 1, 2 for x, y, z
  double frequency_hz = 0.0;
  double gain = 0.0;       ///< gyro amplitude / encoder rate amplitude along that body axis
  double gain_db = 0.0;    ///< 20 log10(gain)
  double phase_deg = 0.0;  ///< gyro phase minus encoder phase, unwrapped along frequency [deg]
  double table_amplitude_dps = 0.0;  ///< fitted encoder rate amplitude [deg/s]
  std::size_t samples = 0;           ///< IMU samples fitted
  std::size_t encoder_rows = 0;      ///< encoder readings fitted
  /// One-sigma uncertainties of gain [ratio] and phase [deg], from the scatter of the gain and
  /// phase fitted in `segments` parts of whole periods (batch means); 0 with fewer than 4
  /// periods recorded (no interval is given then).
  double gain_sigma = 0.0;
  double phase_sigma_deg = 0.0;
  int segments = 0;
};

/// What analyse_bandwidth() found, per body axis where the axis was oscillated.
struct BandwidthAnalysis {
  std::int64_t run = 0;
  std::string device;
  std::vector<BandwidthPoint> points;  ///< by axis, then frequency
  /// -3 dB frequency interpolated on the gain curve (linear in dB over log frequency) [Hz];
  /// none when the curve does not cross -3 dB within the frequencies tested.
  std::array<std::optional<double>, 3> bandwidth_hz;
  /// The low-pass model whose phase is taken out before the delay is read: the Butterworth
  /// order (1: first order) whose gain at the bandwidth found best matches the measured gains;
  /// 0 when there is no bandwidth (no filter phase removed).
  std::array<int, 3> low_pass_order{0, 0, 0};
  /// Pure delay [s]: minus the slope of (phase - the low-pass model's phase) against angular
  /// frequency, by least squares through the origin; none with fewer than two frequencies.
  std::array<std::optional<double>, 3> delay_s;
  /// Probability of the intervals below (0.95).
  double confidence = 0.0;
  /// Intervals [lo, hi] of bandwidth_hz [Hz] and delay_s [s] and the standard deviations they
  /// imply, by a parametric bootstrap over each point's gain and phase uncertainty (Student-t
  /// with the segments' degrees of freedom) through the same interpolation and phase slope,
  /// the low-pass order held; none where the figure is none, a point lacks a sigma, or the
  /// -3 dB crossing leaves the frequencies tested in more than one tail's share of the draws.
  std::array<std::optional<std::array<double, 2>>, 3> bandwidth_interval_hz;
  std::array<std::optional<double>, 3> bandwidth_sigma_hz;
  std::array<std::optional<std::array<double, 2>>, 3> delay_interval_s;
  std::array<std::optional<double>, 3> delay_sigma_s;
};

/// Reads every completed oscillate step of `device` ("" = the run's only IMU) in `run`: fits
/// a * sin(w t) + b * cos(w t) + c at the step's commanded frequency by least squares to the
/// gyro along the oscillating axis (IMU receive times) and to the encoder rate of that axis
/// (its reading times, the dense trace the engine records during an oscillation), the body axis
/// found from the station geometry at the step's mean encoder angles. Throws core::InputError
/// naming the run when it has no oscillate step, or a step too few encoder readings (fewer than
/// 8) to fit.
BandwidthAnalysis analyse_bandwidth(store::Database& db, std::int64_t run,
                                    const std::string& device);

/// `{"run", "device", "gyro": {"bandwidth_hz": [x,y,z], "delay_s": [x,y,z],
///   "low_pass_order": [x,y,z], "confidence": 0.95, "bandwidth_interval_hz": [[lo,hi] x3],
///   "bandwidth_sigma_hz": [x,y,z], "delay_interval_s": [[lo,hi] x3], "delay_sigma_s": [x,y,z],
///   "points": [{"axis", "frequency_hz", "gain", "gain_db", "phase_deg", "gain_sigma",
///   "phase_sigma_deg", "segments", "step", "label"}...]}}`, null for an axis without a value.
nlohmann::json to_json(const BandwidthAnalysis& b);

/// The gain curves (dB against log frequency, one per axis, with the -3 dB line) as inline
/// SVG through gnuplot. Throws core::InputError naming gnuplot when it is missing or fails.
std::string bandwidth_svg(const BandwidthAnalysis& b);

}  // namespace calstand::analysis
