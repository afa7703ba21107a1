#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "core/imu_sample.hpp"
#include "solver/gravity_norm.hpp"
#include "solver/static_detector.hpp"
#include "solver/triad_model.hpp"

/// Gyro calibration by integration between static poses (Tedaldi et al. 2014, imu_tk): the
/// accelerometer, once calibrated (gravity_norm.hpp), tells the gravity direction in the body
/// at the end of one static pose and at the start of the next; the calibrated gyro, integrated
/// over the turn between them, must rotate the first direction into the second.
///
/// - Bias: the mean of the initial rest (the interval flagged initial_rest), with its sigma;
///   the Earth rate at the rest's orientation is part of it (at most 15.04 deg/h).
/// - Scale (3) and misalignment (6, relative to the accelerometer frame A of triad_model.hpp):
///   Ceres (Levenberg-Marquardt, automatic derivatives). Per turn: the rate of each sample is
///   calibrated, w = T_g^-1 (w_meas - b); each sample interval [t_i, t_i+1] (the samples' own
///   time stamps) turns by exp of the trapezoidal mean rate times the interval, quaternions
///   composed in order (exact for a rate constant over the interval, second order otherwise;
///   the order of rotations is kept, no coning error beyond that).
/// - Residual: the gravity direction predicted at the start of the next pose minus the one
///   measured there, its two components across the measured direction [rad] (the turn about
///   gravity itself is invisible), each divided by its sigma: the direction noise of the two
///   pose means (the accel mean's sigma over g) and the gyro white noise integrated over the
///   turn (measured in the rest).
/// - Holds: a hand does not hold still. Each pose's accel mean is referred to its last sample
///   (for the turn that leaves it) and to its first (for the turn that enters it) by rotating
///   every accel sample with the gyro integrated within the pose, the pose's own mean rate
///   removed (a hold does not turn on average: that removes the bias and the Earth rate
///   there, keeping the sway). `refer_hold_means` = false uses the plain means.
/// - Covariance: (J^T J)^-1, multiplied by chi2/dof when above 1 (as gravity_norm.hpp), plus
///   what the accelerometer calibration's covariance and the rest bias's sigma carry into the
///   gyro parameters (linearised: dp = -(J^T J)^-1 J^T dr/dq dq, dr/dq by differences).
/// - Not modelled: the Earth rate (the heading is unknown); summary and `earth_rate_bound_deg`
///   give its size against the residual. g-sensitivity only with fit_g_sensitivity.
namespace calstand::solver {

/// How one static pose's accel mean was referred to its ends (see the header): the still rate
/// removed from the gyro within it [deg/s] (empty: the pose's own mean rate) and the variance
/// the referral adds to its gravity direction, per component [rad^2].
struct GyroHoldReferral {
  std::optional<Eigen::Vector3d> still_rate_dps;
  double variance_rad2 = 0.0;
};

struct GyroIntegrationOptions {
  int min_poses = 9;             ///< static poses (turns + 1) needed
  bool refer_hold_means = true;  ///< see above
  bool fit_bias = false;         ///< also fit a bias during the turns (start: the rest mean)
  /// Also fit the gyro g-sensitivity G (9, (deg/s)/g): w_meas = T_g w + b + G f / g0, with f
  /// the calibrated specific force of each sample (imucal's K_ga). The rest mean then holds
  /// b + G f_rest / g0, so the turns see G (f - f_rest) / g0.
  bool fit_g_sensitivity = false;
  /// The site's latitude [deg] (the import's site.latitude_deg): the Earth rate is modelled
  /// (see above). Empty: not modelled, as before, and the summary says so.
  std::optional<double> latitude_deg;
  /// The poses referred as another fit of the same intervals referred them (its
  /// GyroIntegrationResult::referrals): a diagnosis judges a candidate term on the same data
  /// and weights as the model it extends. Ignored unless one per interval.
  std::vector<GyroHoldReferral> referrals;
  bool scale_sigmas_by_residual = true;
  bool propagate_accel_covariance = true;
  double null_tolerance = 1e-5;
  int max_iterations = 100;
};

struct GyroTurn {
  std::size_t from_interval = 0;
  std::size_t to_interval = 0;
  double start_s = 0.0;
  double end_s = 0.0;
  std::size_t samples = 0;
  double angle_deg = 0.0;  ///< calibrated rotation over the turn
  Eigen::Vector3d axis_A = Eigen::Vector3d::Zero();
  double residual_deg = 0.0;          ///< angle between predicted and measured gravity direction
  double sigma_deg = 0.0;             ///< its expected size from the noise (per component)
  double earth_rate_bound_deg = 0.0;  ///< 2 |w_ie| duration: most the Earth rate can do
};

struct GyroIntegrationResult {
  TriadModel gyro;  ///< frame A
  /// gyro_bias.x y z, gyro_scale.x y z, gyro_misalignment.xy xz yx yz zx zy, and with
  /// fit_g_sensitivity gyro_g_sensitivity.xx xy ... zz (the bias then is the contract's b: the
  /// rest mean minus G f_rest / g0, its sigma including G's).
  std::vector<TriadEstimate> parameters;
  /// Covariance of `parameters` in contract units (deg/s, ppm, rad, (deg/s)/g), same order.
  Eigen::MatrixXd covariance;
  Eigen::Matrix3d g_sensitivity = Eigen::Matrix3d::Zero();  ///< (deg/s)/g, when fitted
  std::vector<std::string> undetermined;
  /// The undetermined ones that are fitted but move with an accelerometer parameter the poses
  /// did not determine (the frame A is not fixed about some axis): status undetermined, sigma 0.
  std::vector<std::string> frame_open;
  Eigen::Vector3d rest_bias_dps = Eigen::Vector3d::Zero();
  Eigen::Vector3d rest_bias_sigma_dps = Eigen::Vector3d::Zero();
  double rest_duration_s = 0.0;
  /// The Earth rate (with a latitude): whether modelled, the latitude, the azimuth of North
  /// about gravity at the rest [deg] (from the horizontal projection of frame A's x axis, or
  /// its y axis when x is within 26 deg of the vertical, counter-clockwise seen from above)
  /// with its sigma, whether the turns determine it (sigma below 0.5 rad), and the Earth rate
  /// at the rest taken out of the rest mean to give gyro_bias [deg/s, frame A].
  bool earth_rate_modelled = false;
  double latitude_deg = 0.0;
  double rest_north_azimuth_deg = 0.0;
  double rest_north_azimuth_sigma_deg = 0.0;
  bool heading_determined = false;
  Eigen::Vector3d rest_earth_rate_dps = Eigen::Vector3d::Zero();
  double hold_sway_rad = 0.0;               ///< RMS net turn of a hold by the hand, per axis [rad]
  std::vector<GyroHoldReferral> referrals;  ///< per interval, as used
  std::vector<GyroTurn> turns;
  double rms_residual_deg = 0.0;
  double max_residual_deg = 0.0;
  double chi2 = 0.0;
  int dof = 0;
  double chi2_per_dof = 0.0;
  double sigma_scale = 1.0;
  bool sigmas_scaled = false;
  double earth_rate_rms_deg = 0.0;  ///< RMS over turns of the Earth-rate bound / sqrt(2)
  int iterations = 0;
  bool converged = false;
  std::string summary;
};

/// `intervals`: the static poses in time order (detect_static_intervals()), one flagged
/// initial_rest; `accel`: the accelerometer calibration of the same poses. Throws
/// core::InputError (where "gyro integration") with fewer than min_poses intervals, without an
/// initial rest, or on intervals outside the samples.
GyroIntegrationResult calibrate_gyro_integration(std::span<const core::ImuSample> samples,
                                                 std::span<const StaticInterval> intervals,
                                                 const GravityNormResult& accel,
                                                 const GyroIntegrationOptions& options);

/// {"method": "gyro_integration", "frame", "parameters": [...], "covariance": {"names",
///  "matrix"}, "undetermined", "frame_open", "rest": {"duration_s", "bias_dps", "bias_sigma_dps"},
///  "quality": {"turns", "rms_residual_deg", "max_residual_deg", "chi2", "dof",
///  "chi2_per_dof", "sigma_scale", "sigmas_scaled", "earth_rate_rms_deg", "summary"},
///  "turns": [{"from", "to", "start_s", "end_s", "samples", "angle_deg", "axis_A",
///  "residual_deg", "sigma_deg", "earth_rate_bound_deg"}], "solver": {...}}
nlohmann::json gyro_integration_to_json(const GyroIntegrationResult& r);

}  // namespace calstand::solver
