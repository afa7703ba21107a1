#pragma once

#include <Eigen/Core>
#include <array>
#include <optional>
#include <string>
#include <vector>

/// Classical calibration methods of the seed notes (inertial-sensor-errors-and-calibration,
/// "IMU calibration"): two-position, six-position least squares in matrix form,
/// twelve-position, the CW/CCW rate test and the general multi-position least squares.
///
/// Every method works on step means the caller has already formed, with the reference input it
/// knows (gravity or Earth rate in the body frame, table angle or rate). Results use the names
/// and units of the error-model contract (../shared/docs/error-model.md):
/// bias in the sensor unit (deg/s or m/s^2), scale factor in ppm, misalignment in rad with
/// M[i][j] coupling reference axis j into sensor axis i (zero diagonal).
///
/// All functions are pure and thread safe. Bad inputs (too few positions, a geometry that does
/// not determine the unknowns, non-finite numbers) throw core::InputError whose where() is the
/// function name and whose message says what is missing.
namespace calstand::solver {

/// Which triad a result belongs to; picks the contract prefix and unit of named parameters.
enum class ClassicalSensor { kGyro, kAccel };

/// One estimated parameter with the contract's full name, e.g. {"accel_scale.x", 120.3, 4.1,
/// "ppm"}. `sigma` is 0 when the method has no redundancy and no measurement sigma was given.
struct ClassicalEstimate {
  std::string name;
  double value = 0.0;
  double sigma = 0.0;
  std::string unit;
};

/// Where the sigmas of a result come from.
enum class SigmaSource {
  kNone,             ///< no redundancy and no measurement sigma: sigmas are 0 (unknown)
  kGiven,            ///< propagated from the caller's measurement sigma
  kResidualScatter,  ///< from the residual scatter of the fit (needs more data than unknowns)
};

// ---------------------------------------------------------------------------------------------
// Two-position (seed: "two-position static calibration, with a tilt angle")

/// Single-axis bias and scale factor from an up and a down measurement.
struct TwoPositionResult {
  double bias = 0.0;             ///< b [sensor unit: m/s^2 or deg/s]
  double scale_ppm = 0.0;        ///< s * 1e6 [ppm]
  double bias_sigma = 0.0;       ///< [sensor unit]; 0 unless a measurement sigma was given
  double scale_sigma_ppm = 0.0;  ///< [ppm]; 0 unless a measurement sigma was given
};

/// Accelerometer two-position test with the sensing axis tilted by `tilt_rad` from the vertical
/// in both positions (seed: f_up = b + (1+s) g cos(tilt), f_down = b - (1+s) g cos(tilt)):
/// b = (f_up + f_down) / 2, s = (f_up - f_down) / (2 g cos(tilt)) - 1.
/// `f_up_mps2`, `f_down_mps2`: mean outputs [m/s^2]; `gravity_mps2`: local g [m/s^2];
/// `mean_sigma`: optional 1-sigma of each mean [m/s^2], propagated to the result (the method
/// has no redundancy, so without it the sigmas are 0).
/// Throws core::InputError for a non-finite input, g <= 0, |tilt| >= 90 deg or a negative sigma.
TwoPositionResult two_position(double f_up_mps2, double f_down_mps2, double gravity_mps2,
                               double tilt_rad = 0.0, double mean_sigma = 0.0);

/// Gyro two-position test on the Earth rate: the same algebra with the reference magnitude
/// `earth_rate_component_dps` = the Earth-rate component along the sensing axis in the "up"
/// position [deg/s] (W sin(lat) for a vertical axis, W cos(lat) for an axis pointing North).
/// The up/down pair reverses the axis along that component. Note the weak observability of the
/// scale factor: its sigma is mean_sigma / (sqrt(2) * W_component), tens of thousands of ppm for
/// a tactical gyro; the bias is the useful output.
/// Throws core::InputError as two_position() and for a zero reference.
TwoPositionResult two_position_gyro(double w_up_dps, double w_down_dps,
                                    double earth_rate_component_dps, double mean_sigma = 0.0);

// ---------------------------------------------------------------------------------------------
// Matrix form (seed: "six-position method, least squares form"): U = M A

/// A fitted triad model meas = (I + S + Mis) ref + b, i.e. the seed's M = [I+S+Mis | b] (3x4).
struct MatrixCalibration {
  Eigen::Matrix<double, 3, 4> M = Eigen::Matrix<double, 3, 4>::Zero();  ///< [I+S+Mis | b]
  Eigen::Vector3d bias = Eigen::Vector3d::Zero();                       ///< b [sensor unit]
  Eigen::Vector3d scale_ppm = Eigen::Vector3d::Zero();                  ///< 1e6 (M[i][i] - 1) [ppm]
  Eigen::Matrix3d misalignment_rad = Eigen::Matrix3d::Zero();           ///< M[i][j], i != j [rad]
  Eigen::Vector3d bias_sigma = Eigen::Vector3d::Zero();                 ///< [sensor unit]
  Eigen::Vector3d scale_sigma_ppm = Eigen::Vector3d::Zero();            ///< [ppm]
  Eigen::Matrix3d misalignment_sigma_rad = Eigen::Matrix3d::Zero();     ///< [rad], zero diagonal
  /// Covariance of row i of M (4x4, order: columns of M) for sensor axis i, in
  /// (dimensionless, sensor unit) mixed units: the first three are M entries, the last is b.
  std::array<Eigen::Matrix4d, 3> row_covariance{};
  Eigen::Matrix3Xd residuals;  ///< U - M A per position (3xN) [sensor unit]
  Eigen::Vector3d residual_rms = Eigen::Vector3d::Zero();  ///< per axis over positions
  /// Per-axis sigma used for the covariance: the given one, or the residual scatter
  /// sqrt(sum r^2 / (N - 4)) [sensor unit].
  Eigen::Vector3d measurement_sigma = Eigen::Vector3d::Zero();
  SigmaSource sigma_source = SigmaSource::kNone;
  int positions = 0;  ///< N
  int dof = 0;        ///< N - 4 per axis
  /// 2-norm condition number of the design A^T (N x 4) after scaling each column to unit norm,
  /// so it measures geometry, not units (1 for an ideal design; large: weakly determined).
  double condition_number = 0.0;
};

/// Options shared by the matrix-form methods.
struct MatrixFitOptions {
  /// 1-sigma of each position mean per axis [sensor unit]. When absent, sigmas come from the
  /// residual scatter (needs N > 4), else they are 0 with SigmaSource::kNone.
  std::optional<Eigen::Vector3d> measurement_sigma;
  /// Designs with a column-scaled condition number above this are refused (InputError).
  double max_condition_number = 1e8;
};

/// The seed's six-position design A (4x6) for a reference magnitude `reference` (g for
/// accelerometers): columns [r e_i; 1] for +x, -x, +y, -y, +z, -z in that order.
Eigen::Matrix<double, 4, 6> six_position_design(double reference);

/// Six-position least squares exactly as the seed writes it: M = U A^T (A A^T)^-1.
/// `U` (3x6): measured means [sensor unit]; `A` (4x6): columns [reference in B; 1] (use
/// six_position_design() for the ideal +-axis positions, or the actual reference of each
/// position, e.g. with a table tilt). Works for accelerometers (gravity) and for gyros on the
/// Earth rate when static (observability is weak there: scale and misalignment sigmas are
/// about mean_sigma / W, so only the bias is of practical use).
/// `sensor` only labels errors. Throws core::InputError when A A^T is singular or its
/// condition exceeds options.max_condition_number.
MatrixCalibration six_position(const Eigen::Matrix<double, 3, 6>& U,
                               const Eigen::Matrix<double, 4, 6>& A,
                               const MatrixFitOptions& options = {});

/// The same matrix model on any number N >= 4 of positions, solved by an SVD of the
/// column-scaled design (numerically safer than forming A A^T; same solution). `U` (3xN),
/// `A` (4xN) as in six_position(). Throws core::InputError when N < 4, the sizes disagree, an
/// entry is not finite, or the positions do not determine M (the error gives the condition
/// number and the singular direction, e.g. references that span fewer than three directions).
MatrixCalibration multi_position(const Eigen::Matrix3Xd& U, const Eigen::Matrix4Xd& A,
                                 const MatrixFitOptions& options = {});

/// Contract-named parameters of a matrix fit: `<sensor>_bias.x..z`, `<sensor>_scale.x..z`,
/// `<sensor>_misalignment.xy..zy`, with sigmas.
std::vector<ClassicalEstimate> named_parameters(const MatrixCalibration& fit,
                                                ClassicalSensor sensor);

// ---------------------------------------------------------------------------------------------
// Twelve-position

/// A static position: the IMU's mean outputs and its known attitude.
struct StaticPosition {
  Eigen::Vector3d gyro_dps = Eigen::Vector3d::Zero();    ///< mean gyro output [deg/s]
  Eigen::Vector3d accel_mps2 = Eigen::Vector3d::Zero();  ///< mean accel output [m/s^2]
  Eigen::Matrix3d C_LB = Eigen::Matrix3d::Identity();    ///< body-to-level (ENU) attitude
};

/// Table angles of one position on the typical table of error-model.md (outer axis horizontal
/// North, inner axis Up at outer 0) [deg].
struct TableAngles {
  double outer_deg = 0.0;
  double inner_deg = 0.0;
};

/// The twelve-position arrangement used here: every body axis up and down, each at two
/// headings 180 deg apart about the vertical (so the horizontal Earth-rate component reverses
/// on the horizontal axes, which the gyro misalignment and g-sensitivity fits need), on the
/// typical table (outer = North, inner = Up at zero):
///   z up   (outer 0,  inner 0 / 180)     z down (outer 180, inner 0 / 180)
///   x up   (outer -90, inner 0; outer 90, inner 180)
///   x down (outer 90, inner 0; outer -90, inner 180)
///   y up   (outer -90, inner -90; outer 90, inner 90)
///   y down (outer 90, inner -90; outer -90, inner 90)
/// On another table the caller picks angles giving the same attitudes; twelve_position() only
/// needs the attitudes, and checks the geometry through the fit itself.
/// Limitation of this table: with the outer axis horizontal the body z axis (along the inner
/// axis) is never horizontal North or South, so for static gyro positions its Earth-rate
/// component is always (W sin(lat)/g) f_z; the gyro g-sensitivity column G[.][z] then cannot be
/// told from M[.][z]. Use twelve_position_attitudes(90) for that fit.
std::array<TableAngles, 12> twelve_position_table_angles();

/// The twelve attitudes C_LB (body to ENU) in the same order: even entries are the heading-0
/// attitude of twelve_position_table_angles(), odd entries that attitude turned by
/// `second_heading_deg` about Up. With 180 they equal the table angles' attitudes; with 90 the
/// horizontal axes point North or South in some position each (a cube on a level plate, or a
/// three-axis table), which the gyro g-sensitivity fit needs.
std::array<Eigen::Matrix3d, 12> twelve_position_attitudes(double second_heading_deg = 180.0);

/// Options of twelve_position().
struct TwelvePositionOptions {
  MatrixFitOptions accel;  ///< for the accelerometer fit
  MatrixFitOptions gyro;   ///< for the gyro fit (and the g-sensitivity fit)
  /// Also fit the gyro g-sensitivity G (meas = (I+S+Mis) w + G f/g0 + b): 7 unknowns per axis
  /// on 12 positions. Needs attitudes where every horizontal axis points North or South
  /// somewhere (twelve_position_attitudes(90)); on the typical table's arrangement the z column
  /// is not separable and the fit is refused naming "w_z" and "f_z".
  bool fit_gyro_g_sensitivity = false;
};

/// Result of twelve_position().
struct TwelvePositionResult {
  MatrixCalibration accel;  ///< reference f_B = C_LB^T (0, 0, g)
  MatrixCalibration gyro;   ///< reference w_B = C_LB^T w_ie_L (Earth rate only, static)
  /// When fitted: G [(deg/s)/g] with [i][j] = f_j -> axis i, and its sigmas. The gyro result
  /// above then comes from the same 7-unknown fit (its M and sigmas include the G coupling).
  std::optional<Eigen::Matrix3d> gyro_g_sensitivity;
  std::optional<Eigen::Matrix3d> gyro_g_sensitivity_sigma;
};

/// Twelve-position calibration of both triads from static positions (typically the
/// arrangement of twelve_position_table_angles()): accelerometer bias/scale/misalignment on
/// gravity, gyro bias/scale/misalignment on the Earth rate (optionally g-sensitivity).
/// `gravity_mps2`: local g; `earth_rate_level_dps`: w_ie in L [deg/s] (core::Site gives rad/s).
/// Throws core::InputError unless exactly 12 positions are given with a valid geometry.
TwelvePositionResult twelve_position(const std::vector<StaticPosition>& positions,
                                     double gravity_mps2,
                                     const Eigen::Vector3d& earth_rate_level_dps,
                                     const TwelvePositionOptions& options = {});

// ---------------------------------------------------------------------------------------------
// Rate tests (seed: "angular rate test", CW and CCW with the Earth-rate term)

/// Single-axis gyro bias and scale from a rate test.
struct RateTestResult {
  double bias_dps = 0.0;
  double scale_ppm = 0.0;
  double bias_sigma_dps = 0.0;
  double scale_sigma_ppm = 0.0;
  SigmaSource sigma_source = SigmaSource::kNone;
};

/// CW/CCW test on integrated angle. The table turns the gyro's sensing axis by
/// +reference_angle ("cw") and by -reference_angle ("ccw"), each in `duration_s`; the gyro
/// output integrated over each turn is angle_cw / angle_ccw [deg]. With the Earth-rate
/// component W_z along the sensing axis (constant during both turns) the seed's model is
///   angle_cw  = (1+s)(+theta + W_z t) + b t,   angle_ccw = (1+s)(-theta + W_z t) + b t
/// so s = (angle_cw - angle_ccw) / (2 theta) - 1 and b = (angle_cw + angle_ccw) / (2t) - (1+s) W_z
/// (the seed's note asks whether the scale acting on W_z matters: it is kept here, exactly).
/// Misalignment couples the other axes' Earth-rate components into b; they average out only
/// over whole turns (reference_angle a multiple of 360 deg). `angle_sigma_deg`: optional
/// 1-sigma of each integrated angle, propagated. Throws core::InputError for theta == 0,
/// t <= 0, non-finite inputs or a negative sigma.
RateTestResult rate_test_cw_ccw(double angle_cw_deg, double angle_ccw_deg,
                                double reference_angle_deg, double duration_s,
                                double earth_rate_component_dps, double angle_sigma_deg = 0.0);

/// The same test on mean rates at +table_rate and -table_rate about the sensing axis:
/// rate_pos = b + (1+s)(+r + W_z), rate_neg = b + (1+s)(-r + W_z).
/// Throws core::InputError for r == 0, non-finite inputs or a negative sigma.
RateTestResult rate_test_cw_ccw_rates(double rate_pos_dps, double rate_neg_dps,
                                      double table_rate_dps, double earth_rate_component_dps,
                                      double mean_sigma_dps = 0.0);

/// One rate step: the table's rate about the sensing axis and the gyro's mean output.
struct RateStep {
  double table_rate_dps = 0.0;  ///< right-handed about the sensing axis [deg/s]
  double gyro_mean_dps = 0.0;   ///< mean output of the sensing axis [deg/s]
};

/// Least-squares line through any number of rate steps: gyro = b + (1+s)(r + W_z). Needs at
/// least two distinct rates; with more than two the sigmas come from the residual scatter
/// unless `mean_sigma_dps` > 0 is given. Throws core::InputError for fewer than two distinct
/// rates or non-finite inputs.
RateTestResult rate_steps(const std::vector<RateStep>& steps, double earth_rate_component_dps,
                          double mean_sigma_dps = 0.0);

}  // namespace calstand::solver
