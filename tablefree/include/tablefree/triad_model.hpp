#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <vector>

#include "core/imu_sample.hpp"

/// What the calibrations without a table share (static_detector, gravity_norm,
/// gyro_integration, ferraris): a sensor triad's forward model, named estimates, the frame
/// convention, identifiability and the noise of a static mean.
///
/// The model is the contract's (../shared/docs/error-model.md), forward:
///   measured = T * truth + b,   T = I + diag(s) * 1e-6 + M,
/// b in the sensor unit (m/s^2, deg/s), s in ppm, M [rad] zero on the diagonal, M[i][j] couples
/// truth axis j into sensor axis i.
///
/// Frame A (the body frame of a calibration without a table) is the accelerometer triad's:
///   body x along the accelerometer x sensitive axis, body y in the plane of the accelerometer
///   x and y sensitive axes (on accel y's side), body z completing a right-handed frame.
/// Accelerometer i senses along row i of T_a, so in A row x is (1 + s_x, 0, 0) and row y has no
/// z part: T_a is lower triangular, and accel_misalignment.xy, .xz and .yz are zero by
/// convention (reported with status "fixed by convention", sigma 0). The gyro misalignment
/// (all six) is relative to A. Any T_a = L Q (L lower triangular, positive diagonal, Q a
/// rotation): lower_triangular_frame() gives the A-frame model of a triad known in another
/// frame, Q being that frame's rotation into A.
namespace calstand::solver {

/// The frame convention in one sentence (for reports and JSON).
inline constexpr const char* kAccelTriadFrameText =
    "accelerometer triad: body x along the accel x sensitive axis, body y in the plane of accel "
    "x and y, z completing a right-handed frame (accel_misalignment .xy .xz .yz are 0 by "
    "convention)";

/// A triad's forward model (accelerometer or gyro), contract units.
struct TriadModel {
  Eigen::Vector3d bias = Eigen::Vector3d::Zero();          ///< m/s^2 or deg/s
  Eigen::Vector3d scale_ppm = Eigen::Vector3d::Zero();     ///< ppm
  Eigen::Matrix3d misalignment = Eigen::Matrix3d::Zero();  ///< rad, zero diagonal

  /// T = I + diag(s) 1e-6 + M.
  Eigen::Matrix3d matrix() const;
  /// The truth for a measurement: T^-1 (measured - b).
  Eigen::Vector3d correct(const Eigen::Vector3d& measured) const;
  /// The model whose matrix is T (diagonal to scale, off-diagonal to misalignment).
  static TriadModel from_matrix(const Eigen::Matrix3d& T, const Eigen::Vector3d& bias);
};

/// T = L Q with L lower triangular (positive diagonal) and Q a rotation (det +1).
struct LowerTriangularFrame {
  Eigen::Matrix3d L;
  Eigen::Matrix3d Q;
};
/// Throws core::InputError when T is singular.
LowerTriangularFrame lower_triangular_frame(const Eigen::Matrix3d& T);

/// How an estimate was obtained.
enum class EstimateStatus {
  kEstimated,          ///< fitted (value and sigma meaningful)
  kFixedByConvention,  ///< zero by the frame convention (accel_misalignment.xy .xz .yz)
  kUndetermined,       ///< the data cannot determine it: held (not fitted), sigma 0
};
const char* estimate_status_name(EstimateStatus s);  ///< "estimated", "fixed by convention", ...

/// One parameter with its contract name, value, 1-sigma and unit.
struct TriadEstimate {
  std::string name;  ///< e.g. "accel_misalignment.yx"
  double value = 0.0;
  double sigma = 0.0;
  std::string unit;
  EstimateStatus status = EstimateStatus::kEstimated;
};

/// The twelve contract names of a triad's bias, scale and misalignment, `prefix` "accel" or
/// "gyro": bias.x y z, scale.x y z, misalignment.xy xz yx yz zx zy.
std::vector<std::string> triad_parameter_names(const std::string& prefix);
/// Estimates in that order from a model (sigmas 0, status estimated; the caller fills them).
std::vector<TriadEstimate> triad_estimates(const std::string& prefix, const TriadModel& m);

/// Parameters the data do not determine, from the weighted Jacobian `J` (rows: residuals
/// divided by their sigma; columns: parameters in the caller's units) and the size
/// `natural_unit[j]` of a change of parameter j that moves a measurement by the order of the
/// measurement itself (bias: g or a typical rate; scale: 1; misalignment: 1 rad), which makes
/// the information matrix H = (J D)^T (J D) free of units. A parameter is undetermined when at
/// least a quarter of it lies in the eigenvectors of H whose eigenvalue is below
/// `tolerance` times the largest (a sensitivity below sqrt(tolerance) of the best-determined
/// direction): never excited, or collinear with others. Returns column indices.
std::vector<int> undetermined_columns(const Eigen::MatrixXd& J, const Eigen::VectorXd& natural_unit,
                                      double tolerance = 1e-5);

/// The mean of one sensor's samples [begin, end) and its 1-sigma, per axis. The sigma of the
/// mean is the sample scatter over sqrt(N_eff), N_eff = N (1 - r1) / (1 + r1) with r1 the
/// lag-one autocorrelation (clamped to [0, 0.95]): a filtered or slowly wandering output
/// averages down more slowly than white noise.
struct StaticMean {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  Eigen::Vector3d sigma_of_mean = Eigen::Vector3d::Zero();
  Eigen::Vector3d sample_sigma = Eigen::Vector3d::Zero();  ///< scatter of one sample
  std::size_t count = 0;
};
enum class TriadSensor { kGyro, kAccel };
/// Throws core::InputError when the range is empty or out of bounds.
StaticMean static_mean(std::span<const core::ImuSample> samples, std::size_t begin, std::size_t end,
                       TriadSensor sensor);

/// [{"name", "value", "sigma", "unit", "status"}] of the estimates.
nlohmann::json triad_estimates_to_json(const std::vector<TriadEstimate>& estimates);

}  // namespace calstand::solver
