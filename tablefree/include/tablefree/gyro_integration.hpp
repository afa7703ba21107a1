#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "core/imu_sample.hpp"
#include "tablefree/gravity_norm.hpp"
#include "tablefree/static_detector.hpp"
#include "tablefree/triad_model.hpp"

/// Gyro calibration by integration between static poses (Tedaldi et al. 2014, imu_tk): the
/// accelerometer, once calibrated (gravity_norm.hpp), tells the gravity direction in the body
/// at the end of one static pose and at the start of the next; the calibrated gyro, integrated
/// over the turn between them, must rotate the first direction into the second.
///
/// - Earth rate (with `latitude_deg`; error-model.md: w_ie_L = W (0, cos(lat), sin(lat)) ENU,
///   W = 7.292115e-5 rad/s, WGS-84, core::kEarthRateRadPerS). The gyro measures the rate
///   against inertial space; gravity is fixed in the level frame, which turns with the Earth.
///   In frame A the Earth rate is W sin(lat) along the measured gravity direction (no heading
///   needed) plus W cos(lat) towards North across it. North's azimuth about gravity at the
///   initial rest, psi, is one nuisance parameter (it does not cancel: the horizontal part
///   moves in the body as the unit turns, by W cos(lat) times a turn's duration, 1e-4 rad over
///   2 s at 45 deg, four times an LN200-class turn's noise). The rest's horizontal basis is
///   carried from pose to pose by the gyro (re-levelled on each pose's measured gravity), so
///   every turn knows its Earth rate from psi. The rest mean holds b + T_g w_ie(rest)
///   (+ G f_rest / g0): the integrand is T_g^-1 (w_meas - rest mean [- G (f - f_rest) / g0])
///   + w_ie(rest), the inertial rate, and the predicted direction at a turn's end is
///   q^* (R(w_ie(start) T) u_start): the gravity direction turned by the Earth over the turn's
///   duration T in the inertial frame of its start, seen from the body the gyro turned.
///   psi starts where the residual, nearly linear in (cos psi, sin psi), is least (three
///   evaluations), then is fitted with the rest. gyro_bias is then the contract's b = rest mean
///   - T_g w_ie(rest) (- G f_rest / g0): with the heading determined (sigma below 0.5 rad, the
///   LN200 class: a few degrees), the whole Earth rate with psi's sigma carried in; else only
///   the vertical part, the horizontal part's (W cos(lat))^2 / 2 per horizontal axis added to
///   the bias's variance. Without a latitude the Earth rate is not modelled: it stays in the
///   bias and looks like an isotropic g-sensitivity of W sin(lat) per g (0.003 (deg/s)/g at
///   45 deg), which the summary says.
/// - Scale (3) and misalignment (6, relative to the accelerometer frame A of triad_model.hpp):
///   Ceres (Levenberg-Marquardt, automatic derivatives). Per turn: the rate of each sample is
///   calibrated as above; each sample interval [t_i, t_i+1] (the samples' own time stamps)
///   turns by exp of the trapezoidal mean rate times the interval plus the second-order coning
///   term (w_i x w_i+1) dt^2 / 12 (Bortz; a rate linear over the interval), quaternions
///   composed in order.
/// - Residual: the gravity direction predicted at the start of the next pose minus the one
///   measured there, its two components across the measured direction [rad] (the turn about
///   gravity itself is invisible), each divided by its sigma (the turns' noise model below).
/// - Holds: a hand does not hold still. Each pose's accel mean is referred to its last sample
///   (for the turn that leaves it) and to its first (for the turn that enters it) by rotating
///   every accel sample with the gyro integrated within the pose, less the rate the pose has
///   when still. First that is the pose's own mean rate (a hold does not turn on average),
///   but the detector cuts a hold inside the hand's sway, so the hold turns a little over its
///   interval and the mean takes that net turn for bias, putting the referred direction off
///   by half of it. With the Earth rate modelled the still rate is also known from the rest
///   (its mean plus the change of the Earth rate and of G f), to the bias's wander; each hold
///   takes the mix of the two with the least variance, the hand's net turn estimated from how
///   far the holds' mean rates stray from the known rate beyond both noises (a hold straying
///   further than its own gyro excursion allows keeps its mean: an effect the model lacks, not
///   sway). `referrals` re-uses another fit's. `refer_hold_means` = false uses plain means.
/// - The turns' noise model (measured source by source on simulated sessions:
///   docs/table-free-turn-noise.md), per component across gravity, all in rad:
///   gyro white noise over the turn, N^2 T (N: the density from the rest mean's sigma, which
///   counts correlated samples, so an output filter does not hide it); the bias's wander since
///   the rest over the turn, s_b^2 T^2 (s_b^2: twice the rest's overlapping Allan variance at a
///   quarter of its length less its white part); per pose, the accel mean's white noise and
///   the wander the pose means share (the gravity norm's REML noise model, pose_sigma) over g,
///   and what the referral adds (N^2 T_hold / 12 with the pose's mean rate; the mix's variance
///   otherwise). Time-stamp jitter, the output filter, the lever arm and the quaternion
///   discretisation (with the coning term) change the turns by less than their noise.
/// - Covariance: (J^T J)^-1, multiplied by chi2/dof when above 1 (as gravity_norm.hpp), plus
///   what the accelerometer calibration's covariance and the rest bias's sigma carry into the
///   gyro parameters (linearised: dp = -(J^T J)^-1 J^T dr/dq dq, dr/dq by differences); psi is
///   marginalised (not a contract parameter: reported beside them).
/// - g-sensitivity only with fit_g_sensitivity.
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
