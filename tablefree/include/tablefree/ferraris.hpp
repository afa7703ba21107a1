#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "core/imu_sample.hpp"
#include "tablefree/triad_model.hpp"

/// The Ferraris method (Ferraris et al., "Procedure for effortless in-field calibration of
/// three-axis rate gyros and accelerometers", Sensors and Materials 7(5), 1995; imucal) for a
/// labelled session without a table: six static holds with a housing axis up (x_p: +x up, the
/// accelerometer reads +g) or down (x_a), and three turns of a known angle about each axis held
/// up (x_rot, y_rot, z_rot), done by hand against a box.
///
/// The nominal frame N of the labels is the box's (each hold puts a housing axis along the
/// vertical). In N the model is linear:
///   accel: a_p = b_a + T_a (s_p g e_i) + e_p        (hold p with axis i up, s_p = +-1)
///   gyro:  Theta_k = sum (w - b_g) dt = T_g (phi_k e_i) + n_k   (turn k about axis i)
/// with b_g the mean of the six holds' gyro means (the Earth rate cancels between an axis up
/// and down, up to the heading change), Theta by the trapezoid over the samples' own time
/// stamps.
///
/// Hold noise: each hold mean's sigma is its samples' scatter over the effective count
/// (static_mean()), inflated per axis by the pooled scatter of the holds' block means (four per
/// hold) against what that noise predicts for them, when larger: a wandering bias (flicker,
/// Gauss-Markov) moves the hold means more than their white noise.
///
/// Placement: a hand-placed hold is tilted by a degree or so, which moves the accelerometer
/// reading across the nominal axis by g x tilt, a hundred times its noise. Fitted as if the
/// holds were exact, that error shows as chi2/dof in the thousands and would pass for a missing
/// effect. Here each hold's tilt is a random effect: the reading across the nominal axis has
/// the variance g^2 sigma_p^2 on top of the hold mean's noise, sigma_p (per horizontal axis)
/// estimated from the fit's own redundancy (18 readings, 12 unknowns: 6 degrees of freedom, the
/// three axis pairs' disagreement on the bias across their axis) as the value that makes chi2
/// equal to its degrees of freedom (the Paule-Mandel moment estimator), 0 when the holds agree
/// to their noise. A turn's axis is placed the same way, so sigma_p also enters each gyro
/// column across its axis. The sigmas of misalignments and of the frame rotation are then
/// those the placement allows (~ sigma_p / sqrt(2)), not those of the noise.
///
/// Results are given in frame A (triad_model.hpp: the accelerometer triad's, as the methods
/// without labels give them): T_a^N = L Q, accel parameters from L (accel_misalignment .xy .xz
/// .yz fixed by convention), gyro T_g^A = T_g^N Q^T, and Q (how the triad sits in the box) as
/// a small rotation; the N-frame models (as imucal reports K R) are given too. Covariances are
/// propagated through that change of frame.
///
/// Turn angle: the magnitude from the section (angle_deg) or options.turn_angle_deg (360); the
/// sign, with TurnSign::kDetect (default), from the integrated gyro itself (stated in
/// `notes`: imucal assumes -360, a clockwise turn, and a session turned the other way then gets
/// a gyro matrix near -I); with kGiven the section's sign is used and a contradiction is noted.
namespace calstand::solver {

struct FerrarisSection {
  std::string label;  ///< x_p x_a y_p y_a z_p z_a x_rot y_rot z_rot
  std::size_t begin = 0;
  std::size_t end = 0;     ///< one past the last sample
  double angle_deg = 0.0;  ///< turns: signed, right-handed about +axis; 0: options' default
};

/// Sections from per-sample step numbers and step labels (each step's samples from its first
/// to its last occurrence). Throws core::InputError for a label whose step has no samples.
std::vector<FerrarisSection> ferraris_sections_from_steps(
    std::span<const int> steps, const std::vector<std::pair<int, std::string>>& labels);

enum class TurnSign { kDetect, kGiven };

struct FerrarisOptions {
  double gravity_mps2 = 0.0;      ///< local g [m/s^2]; required
  double turn_angle_deg = 360.0;  ///< default turn angle (signed) when a section gives none
  TurnSign turn_sign = TurnSign::kDetect;
  bool estimate_placement = true;  ///< false: the holds taken as exact (the naive fit)
};

struct FerrarisHold {
  std::string label;
  double start_s = 0.0;
  double end_s = 0.0;
  Eigen::Vector3d mean_accel_mps2 = Eigen::Vector3d::Zero();
  Eigen::Vector3d mean_gyro_dps = Eigen::Vector3d::Zero();
  double across_residual_deg = 0.0;  ///< fit residual across the nominal axis, as an angle
  double norm_residual_mg = 0.0;     ///< |calibrated f| - g
};

struct FerrarisTurn {
  std::string label;
  double start_s = 0.0;
  double end_s = 0.0;
  Eigen::Vector3d integrated_deg = Eigen::Vector3d::Zero();  ///< sum (w - b_g) dt, raw axes
  double measured_angle_deg = 0.0;  ///< the component about the nominal axis
  double used_angle_deg = 0.0;      ///< the reference angle the fit used
  double axis_tilt_deg = 0.0;       ///< mean calibrated accel over the section vs the axis
};

struct FerrarisResult {
  TriadModel accel;                       ///< frame A
  TriadModel gyro;                        ///< frame A
  std::vector<TriadEstimate> parameters;  ///< accel (12, 3 by convention) then gyro (12)
  Eigen::MatrixXd covariance;             ///< of `parameters` (24 x 24), contract units
  TriadModel accel_nominal_frame;         ///< frame N (full misalignment), as imucal's K R
  TriadModel gyro_nominal_frame;
  Eigen::Vector3d frame_rotation_deg = Eigen::Vector3d::Zero();  ///< Q as a rotation vector
  Eigen::Vector3d frame_rotation_sigma_deg = Eigen::Vector3d::Zero();
  // Accelerometer fit quality.
  /// Factor on every hold mean's sigma, per axis (>= 1): the holds' block means (four per
  /// hold) scatter more than their sample noise when the bias wanders.
  Eigen::Vector3d hold_noise_inflation = Eigen::Vector3d::Ones();
  bool placement_estimated = false;
  double placement_sigma_deg = 0.0;     ///< per horizontal axis
  double placement_rms_tilt_deg = 0.0;  ///< sqrt(2) sigma_p: the typical tilt of a placement
  double accel_chi2 = 0.0;              ///< with the placement variance
  double accel_chi2_naive = 0.0;        ///< holds taken as exact
  int accel_dof = 6;
  double accel_chi2_per_dof = 0.0;
  double accel_chi2_per_dof_naive = 0.0;
  double norm_rms_residual_mg = 0.0;
  std::vector<FerrarisHold> holds;
  std::vector<FerrarisTurn> turns;
  std::vector<std::string> notes;  ///< turn signs, contradictions, what was assumed
  std::string summary;
};

/// Throws core::InputError (where "ferraris") when a label is missing or repeated, a section
/// is empty or outside the samples, or g is not positive.
FerrarisResult calibrate_ferraris(std::span<const core::ImuSample> samples,
                                  std::span<const FerrarisSection> sections,
                                  const FerrarisOptions& options);

/// {"method": "ferraris", "frame", "parameters": [...], "covariance": {"names", "matrix"},
///  "nominal_frame": {"accel": {"bias", "matrix"}, "gyro": {...}},
///  "frame_rotation_deg", "frame_rotation_sigma_deg",
///  "placement": {"estimated", "sigma_deg", "rms_tilt_deg"},
///  "quality": {"accel_chi2_per_dof", "accel_chi2_per_dof_naive", "accel_dof",
///  "norm_rms_residual_mg", "summary"}, "holds": [...], "turns": [...], "notes": [...]}
nlohmann::json ferraris_to_json(const FerrarisResult& r);

}  // namespace calstand::solver
