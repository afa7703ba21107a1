#pragma once
// The noise of the pose means of a calibration without a table (gravity_norm.hpp), estimated
// from the fit's own residuals.
//
// Why. Each pose mean carries white noise, which the scatter inside the pose measures, and the
// accelerometer's wandering bias (bias instability / flicker, Gauss-Markov, random walk), which
// barely shows inside a pose of a few seconds but moves every pose mean, and which poses close
// in time share. Weighing the residuals by the white part and scaling the sigmas by
// sqrt(chi2/dof) treats that shared wander as independent scatter, and the sigmas come out too
// small (pulls with an RMS of 1.3-1.5 on ADIS16488- and LN200-class sessions).
//
// The model. The residual of pose k is the pose mean's error along its gravity direction u_k,
// so with the wander w_i(t) of axis i
//   cov(r_k, r_l) = delta_kl white_k + sum_i u_k,i u_l,i C_i(k, l),
// C_i(k, l) the covariance of the means of w_i over the two poses
// (WanderModel::interval_mean_covariance()). One process, shared by the three axes
// (C_i = C): some thirty scalar residuals cannot tell three processes apart (each axis is
// seen only through its share u_k,i of every residual, and a triad is three of the same part
// with one spec sheet), and one process keeps the estimate to two numbers. Then
//   Sigma = diag(white) + a (u_k . u_l) C(k, l),
// with the kind of C (none, Gauss-Markov of a correlation time, flicker, random walk) and its
// amplitude a chosen by restricted maximum likelihood (REML) of the residuals, with the fitted
// parameters' columns profiled out (as noise_estimate.hpp does for step means), the candidates
// compared by their likelihood penalised per parameter (BIC). One more candidate is an
// independent extra variance of each pose mean (a hand that places each pose a little
// differently, sway that does not average out): not a wander, but noise of this method all the
// same, so the weights take it.
//
// The fit then weighs by Sigma (generalised least squares).

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "solver/step_noise.hpp"

namespace calstand::solver {

/// One pose mean as the noise model sees it.
struct PoseSpan {
  double start_s = 0.0;  ///< seconds since the recording's first sample
  double end_s = 0.0;
  Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();  ///< unit: the residual's axis
  double white_variance = 0.0;  ///< of the residual from the white noise alone [u^2]
};

/// The noise of the pose means beyond their white part, in the residuals' unit u (m/s^2).
struct PoseNoise {
  /// Shared by the three axes (see above); kind none: no wander.
  WanderModel wander;
  double extra_variance = 0.0;  ///< independent extra variance of each pose mean [u^2]
  /// True when the residuals were used to estimate the model (it may still be white alone:
  /// tested, no evidence of more). False: white alone, `description` says why.
  bool estimated = false;
  int residuals = 0;                 ///< the residuals the estimate used
  int dof = 0;                       ///< residuals minus fitted parameters
  double log_likelihood_gain = 0.0;  ///< penalised REML gain over white noise alone
  double pose_sigma = 0.0;           ///< RMS over the poses of the wander (or extra) [u]
  std::string description;           ///< the model in words

  /// Sigma of `poses` (in order): white on the diagonal, plus the wander or the extra variance.
  Eigen::MatrixXd covariance(const std::vector<PoseSpan>& poses) const;
};

struct PoseNoiseOptions {
  /// Residuals beyond the fitted parameters needed before a wander is estimated.
  int min_dof = 8;
  /// Unit of the description: a factor from u and its name (mg for m/s^2 by default).
  double description_scale = 1e3 / 9.80665;
  std::string description_unit = "mg";
};

/// The noise model of `residuals` (one per pose, in the poses' order) of a fit whose Jacobian
/// (unweighted, in any parameter units; only the fitted parameters' columns) is `jacobian`.
/// White alone, with the reason, when the residuals leave fewer than options.min_dof degrees
/// of freedom.
PoseNoise estimate_pose_noise(const std::vector<PoseSpan>& poses, const Eigen::VectorXd& residuals,
                              const Eigen::MatrixXd& jacobian,
                              const PoseNoiseOptions& options = {});

/// {"estimated", "kind", wander figures ("sigma", "tau_s" | "b", "tau_min_s", "tau_max_s" |
///  "k"), "extra_sigma", "pose_sigma", "residuals", "dof", "log_likelihood_gain",
///  "description"}, figures in u.
nlohmann::json pose_noise_to_json(const PoseNoise& noise);

}  // namespace calstand::solver
