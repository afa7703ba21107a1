#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <vector>

#include "core/imu_sample.hpp"
#include "tablefree/pose_noise.hpp"
#include "tablefree/static_detector.hpp"
#include "tablefree/triad_model.hpp"

/// Accelerometer calibration by the gravity norm (Tedaldi et al. 2014, imu_tk; Fong et al.
/// 2008): at every static pose the calibrated specific force has the magnitude of local
/// gravity, whatever the pose's orientation,
///   |T_a^-1 (a_k - b)| = g   for every pose mean a_k,
/// solved for bias (3), scale (3) and misalignment (3) by non-linear least squares (Ceres,
/// Levenberg-Marquardt, automatic derivatives) from the nominal model (b = 0, T = I).
///
/// Frame: the accelerometer triad's (triad_model.hpp): T_a lower triangular, so
/// accel_misalignment.xy, .xz, .yz are zero by convention and only .yx, .zx, .zy are
/// estimated. The orientation of the poses is never needed, and the norm cannot see a rotation
/// of the whole triad: that is what the convention fixes.
///
/// Weights and sigmas: the pose means share the accelerometer's wandering bias (poses close in
/// time see nearly the same bias), so their residuals are not independent. The residuals'
/// covariance is the white noise of each pose mean along its gravity direction (static_mean():
/// sample scatter over the effective count) plus a wander shared by the three axes (or an
/// independent extra variance per pose), chosen by restricted maximum likelihood from the
/// residuals of a first fit weighed by the white noise alone (pose_noise.hpp); the fit is then
/// repeated by generalised least squares with that covariance Sigma (residuals whitened by its
/// Cholesky factor), and the covariance of the parameters is (J^T Sigma^-1 J)^-1. chi2/dof is
/// still reported against the white noise alone (how much more the poses scatter than their
/// own noise), the noise model beside it in words. When the residuals are too few to estimate
/// a noise model (fewer than 8 degrees of freedom) or estimate_pose_noise is false, the
/// weights are the white noise and, with scale_sigmas_by_residual, every sigma is multiplied by
/// sqrt(chi2/dof) when above 1 (`sigmas_scaled`).
///
/// accel_quadratic (fit_quadratic): the contract's measured_i += 1e-6 g0 k_i (f_i / g0)^2 [k in
/// ug/g^2], f the true specific force in frame A; the calibrated force then solves
/// f = T_a^-1 (a - b - q(f)) (correct_accel()).
///
/// Identifiability: from the Jacobian in natural units (undetermined_columns()); e.g. poses that
/// never tip the y axis (gravity always in the x-z plane) cannot give accel_bias.y,
/// accel_scale.y, accel_misalignment.yx or .zy. That is judged at the nominal model (the
/// poses' raw directions); those parameters are reported undetermined (sigma 0) and held, not
/// fitted: an undetermined bias at its axis's mean reading over the poses, the others at 0
/// (left free, an axis that never feels gravity could add any f_i^2 to the norm and bend the
/// rest); the covariance of the others is conditional on them.
namespace calstand::solver {

struct GravityNormOptions {
  double gravity_mps2 = 0.0;     ///< local g [m/s^2]; required (> 0)
  int min_poses = 9;             ///< refuse below this many static poses
  bool use_initial_rest = true;  ///< the initial rest is a pose like the others
  /// Estimate the pose means' noise (shared wander) from the residuals and weigh by it (GLS).
  bool estimate_pose_noise = true;
  /// Without a noise model (too few poses, or estimate_pose_noise false): sigmas times
  /// sqrt(chi2/dof) when above 1.
  bool scale_sigmas_by_residual = true;
  bool fit_quadratic = false;    ///< also fit accel_quadratic .x .y .z [ug/g^2]
  double null_tolerance = 1e-5;  ///< see undetermined_columns()
  int max_iterations = 100;
};

struct GravityNormPose {
  std::size_t interval = 0;  ///< index into the intervals given
  double start_s = 0.0;
  double end_s = 0.0;
  std::size_t samples = 0;
  Eigen::Vector3d mean_mps2 = Eigen::Vector3d::Zero();        ///< raw mean
  Eigen::Vector3d sigma_mean_mps2 = Eigen::Vector3d::Zero();  ///< per axis
  Eigen::Vector3d up_A = Eigen::Vector3d::Zero();             ///< calibrated gravity direction in A
  double norm_mps2 = 0.0;                                     ///< |calibrated f|
  double residual_mg = 0.0;  ///< |f| - g [mg, 1 mg = 1e-3 x 9.80665 m/s^2]
  double sigma_mg = 0.0;     ///< the pose mean's own noise along gravity [mg]
};

struct GravityNormResult {
  TriadModel accel;  ///< frame A (undetermined parameters at their held values)
  /// accel_quadratic .x .y .z [ug/g^2]; zero unless fitted (correct_accel() applies it).
  Eigen::Vector3d quadratic_ug_per_g2 = Eigen::Vector3d::Zero();
  bool quadratic_fitted = false;
  /// accel_bias.x y z, accel_scale.x y z, accel_misalignment.xy xz yx yz zx zy (the .xy .xz
  /// .yz "fixed by convention"), then accel_quadratic.x y z when fitted.
  std::vector<TriadEstimate> parameters;
  /// Covariance of the free parameters in contract units, in the order of `covariance_names`:
  /// bias x y z [m/s^2], scale x y z [ppm], misalignment yx zx zy [rad] (9), then quadratic
  /// x y z [ug/g^2] when fitted (12); rows and columns of undetermined ones 0.
  Eigen::MatrixXd covariance;
  std::vector<std::string> covariance_names;
  std::vector<std::string> undetermined;  ///< names
  std::vector<GravityNormPose> poses;
  double gravity_mps2 = 0.0;
  double rms_residual_mg = 0.0;
  double max_abs_residual_mg = 0.0;
  double chi2 = 0.0;  ///< against the pose means' white noise alone
  /// Against the noise model the fit was weighed with (`noise`; the white noise when there is
  /// none): about `dof` when the model and the noise model describe the poses.
  double chi2_noise_model = 0.0;
  int dof = 0;  ///< poses - estimated parameters
  double chi2_per_dof = 0.0;
  /// The noise model of the pose means the fit weighs by (white alone when not estimated).
  PoseNoise noise;
  /// Factor applied to every sigma by sqrt(chi2/dof): only without a noise model (see above),
  /// else 1.
  double sigma_scale = 1.0;
  bool sigmas_scaled = false;
  int iterations = 0;
  bool converged = false;
  std::string summary;  ///< the fit quality and the noise model in words
};

/// The calibrated specific force [m/s^2] of a raw accel reading: T_a^-1 (measured - b - q(f)),
/// q the quadratic (zero when not fitted), solved by fixed-point iteration.
Eigen::Vector3d correct_accel(const GravityNormResult& r, const Eigen::Vector3d& measured);
/// The same from a model and quadratic coefficients [ug/g^2].
Eigen::Vector3d correct_accel(const TriadModel& accel, const Eigen::Vector3d& quadratic_ug_per_g2,
                              const Eigen::Vector3d& measured);

/// Calibrates on the static intervals of a recording (e.g. detect_static_intervals(): the
/// intervals flagged initial_rest are used when options.use_initial_rest). Accel samples in
/// m/s^2 (or relative to a nominal conversion). Throws core::InputError (where "gravity
/// norm") when fewer than options.min_poses intervals are usable ("9 static poses are needed,
/// ... found 6"), when g is not positive, or an interval is out of range.
GravityNormResult calibrate_accel_gravity_norm(std::span<const core::ImuSample> samples,
                                               std::span<const StaticInterval> intervals,
                                               const GravityNormOptions& options);

/// The threshold chosen by the calibration residual, as imu_tk does: the detector is run with
/// each multiple of the rest level in `multiples` (ThresholdRule::kMultiple, the other
/// detector options as given), the gravity norm fitted on each set of at least min_poses
/// intervals, and the multiple with the smallest RMS |f|-g is kept.
struct ThresholdSearch {
  struct Candidate {
    double multiple = 0.0;
    std::size_t intervals = 0;
    double rms_residual_mg = 0.0;  ///< 0 when too few intervals to fit
    bool fitted = false;
  };
  std::vector<Candidate> candidates;
  double chosen_multiple = 0.0;
  StaticDetection detection;  ///< with the chosen multiple
  GravityNormResult fit;
};
/// Throws core::InputError when no multiple gives enough intervals.
ThresholdSearch detect_and_calibrate_accel(std::span<const core::ImuSample> samples,
                                           const StaticDetectorOptions& detector,
                                           const GravityNormOptions& options,
                                           const std::vector<double>& multiples = {2, 3, 4, 5, 6, 7,
                                                                                   8, 9, 10});

/// {"method": "gravity_norm", "frame": ..., "gravity_mps2", "parameters": [estimates],
///  "covariance": {"names": [...9 or 12], "matrix": [[...]]}, "undetermined": [names],
///  "quality": {"poses", "rms_residual_mg", "max_abs_residual_mg", "chi2", "dof",
///  "chi2_per_dof", "chi2_noise_model", "sigma_scale", "sigmas_scaled", "summary"},
///  "noise_model": pose_noise_to_json() (figures in m/s^2),
///  "poses": [{"interval", "start_s", "end_s", "samples", "mean_mps2", "up_A", "norm_mps2",
///  "residual_mg", "sigma_mg"}], "solver": {"iterations", "converged"}}
nlohmann::json gravity_norm_to_json(const GravityNormResult& r);

}  // namespace calstand::solver
