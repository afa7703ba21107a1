#pragma once

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace calstand::sim {

/// Per-axis noise of one sensor triad, in the units named in each field.
/// Zero disables a process. Values are 1-sigma unless said otherwise.
struct TriadNoise {
  Eigen::Vector3d white = Eigen::Vector3d::Zero();  ///< density [unit/sqrt(Hz)] (ARW/VRW)
  Eigen::Vector3d bias_instability = Eigen::Vector3d::Zero();  ///< flicker coefficient B [unit]
  Eigen::Vector3d random_walk = Eigen::Vector3d::Zero();  ///< [unit/sqrt(s)] (rate random walk)
  Eigen::Vector3d gauss_markov_sigma = Eigen::Vector3d::Zero();  ///< [unit]
  double gauss_markov_tau_s = 100.0;                             ///< correlation time [s]
  Eigen::Vector3d turn_on_bias = Eigen::Vector3d::Zero();  ///< new constant per power-up [unit]
  /// Scale-factor change drawn anew at each power-up, on top of the calibratable scale [ppm].
  Eigen::Vector3d turn_on_scale_ppm = Eigen::Vector3d::Zero();
  double quantization = 0.0;  ///< output LSB [unit]; 0: none
};

/// Everything the simulator knows about one IMU: the true values of every error-model term
/// (contract units: gyro in deg/s, accel in m/s^2) and its noise and output behaviour.
/// Gyro noise fields are in deg/s units (white: deg/s/sqrt(Hz), random walk: deg/s/sqrt(s));
/// accel fields in m/s^2 units. The truth file (schemas/truth.schema.json) uses datasheet units
/// and is converted on load.
struct ImuTruth {
  std::string name = "imu";
  double temperature_ref_c = 25.0;

  // Gyro terms [contract units].
  Eigen::Vector3d gyro_bias = Eigen::Vector3d::Zero();             ///< deg/s
  Eigen::Vector3d gyro_scale = Eigen::Vector3d::Zero();            ///< ppm
  Eigen::Matrix3d gyro_misalignment = Eigen::Matrix3d::Zero();     ///< rad, zero diagonal
  Eigen::Vector3d gyro_scale_asymmetry = Eigen::Vector3d::Zero();  ///< ppm
  Eigen::Vector3d gyro_quadratic = Eigen::Vector3d::Zero();        ///< ppm/(deg/s)
  Eigen::Matrix3d gyro_g_sensitivity = Eigen::Matrix3d::Zero();    ///< (deg/s)/g, [i][j]: f_j -> i
  std::vector<Eigen::Vector3d> gyro_temp_bias;                     ///< [k-1]: deg/s/degC^k
  Eigen::Vector3d gyro_temp_scale = Eigen::Vector3d::Zero();       ///< ppm/degC

  // Accelerometer terms [contract units].
  Eigen::Vector3d accel_bias = Eigen::Vector3d::Zero();             ///< m/s^2
  Eigen::Vector3d accel_scale = Eigen::Vector3d::Zero();            ///< ppm
  Eigen::Matrix3d accel_misalignment = Eigen::Matrix3d::Zero();     ///< rad
  Eigen::Vector3d accel_scale_asymmetry = Eigen::Vector3d::Zero();  ///< ppm
  Eigen::Vector3d accel_quadratic = Eigen::Vector3d::Zero();        ///< ug/g^2
  std::vector<Eigen::Vector3d> accel_temp_bias;                     ///< [k-1]: m/s^2/degC^k
  Eigen::Vector3d accel_temp_scale = Eigen::Vector3d::Zero();       ///< ppm/degC
  Eigen::Vector3d accel_lever_arm = Eigen::Vector3d::Zero();        ///< m, body frame

  TriadNoise gyro_noise;   ///< deg/s units
  TriadNoise accel_noise;  ///< m/s^2 units

  double sample_rate_hz = 100.0;           ///< output data rate
  double gyro_bandwidth_hz = 0.0;          ///< gyro output low-pass -3 dB; 0 or >= Nyquist: none
  double accel_bandwidth_hz = 0.0;         ///< accel output low-pass -3 dB; 0 or >= Nyquist: none
  int filter_order = 2;                    ///< Butterworth order of the output filters (2, 4, 6, 8)
  std::uint32_t sequence_modulus = 65536;  ///< the counter wraps to 0 here
  double latency_s = 0.001;                ///< receive time minus sample instant
  double clock_drift_ppm = 0.0;            ///< device clock rate error

  // Power-on transient (truth file `power_on`): at each power-up the bias starts offset by
  // these amounts and the offset decays as exp(-t / power_on_time_constant_s), t from the
  // power-up, as a unit warming its sensing elements does. Zero: no transient. The unit's
  // self-heating after a power-up follows the station's chamber model (imu_self_heating_c,
  // imu_time_constant_s): it starts at the air's temperature and settles above it.
  Eigen::Vector3d gyro_power_on_bias = Eigen::Vector3d::Zero();   ///< deg/s at t = 0
  Eigen::Vector3d accel_power_on_bias = Eigen::Vector3d::Zero();  ///< m/s^2 at t = 0
  double power_on_time_constant_s = 60.0;  ///< decay of the bias transient [s], > 0

  // Thermal hysteresis (truth file `thermal_hysteresis`): the bias follows which way the IMU
  // temperature came. A play operator y of width hysteresis_width_c follows the temperature T
  // (y stays put while |T - y| <= width / 2, is dragged along beyond); the bias adds
  // delta (T - y) / width, so the way up reads delta / 2 above the middle, the way down delta / 2
  // below, at one temperature. Zero delta: none.
  Eigen::Vector3d gyro_hysteresis_bias = Eigen::Vector3d::Zero();   ///< up less down [deg/s]
  Eigen::Vector3d accel_hysteresis_bias = Eigen::Vector3d::Zero();  ///< up less down [m/s^2]
  double hysteresis_width_c = 2.0;                                  ///< [degC], > 0

  /// Sets the parameter `full_name` (e.g. "gyro_misalignment.xz") in contract units;
  /// throws core::InputError naming the parameter when it is not in the catalogue or not a
  /// property of the IMU (`table_tilt.*` belongs to the station: table.tilt_rad).
  void set_parameter(const std::string& full_name, double value);
  /// The value of a parameter in contract units (0 for unset temperature orders).
  double parameter(const std::string& full_name) const;
  /// Every non-zero parameter by full name, in contract units.
  std::vector<std::pair<std::string, double>> nonzero_parameters() const;

  /// Checks what a schema cannot (or what was set in code): every parameter finite, every
  /// noise figure finite and >= 0, correlation time > 0, sample rate finite and > 0,
  /// bandwidths finite and >= 0, filter order 2, 4, 6 or 8, sequence modulus >= 2, latency
  /// >= 0. Throws core::InputError naming `file_name: field` as the truth file spells it, with
  /// the value in the file's unit, e.g. `dut.json: noise.gyro.arw_deg_per_sqrt_h: -0.07 must
  /// not be negative`.
  void validate(const std::string& file_name) const;
};

/// Reads a truth document (format "calstand-truth/1", validated against
/// schemas/truth.schema.json, then ImuTruth::validate()). `file_name` is used in error messages;
/// every schema violation is listed. A `table_tilt.*` parameter is refused: the tilt of the
/// table is set in the station file (table.tilt_rad).
ImuTruth imu_truth_from_json(const nlohmann::json& doc, const std::string& file_name);
/// Writes a truth document that imu_truth_from_json() reads back to the same values.
nlohmann::json imu_truth_to_json(const ImuTruth& truth);

/// Physical inputs to the IMU at one instant, in the body frame B.
struct ImuInputs {
  Eigen::Vector3d rate_dps;    ///< true angular rate incl. Earth rate [deg/s]
  Eigen::Vector3d force_mps2;  ///< true specific force at the sensor [m/s^2]
  double temperature_c;        ///< IMU temperature [degC]
};

/// Deterministic sensor errors (every catalogue term except the reference ones, which are
/// physics), before noise: the part a perfect calibration removes.
/// Returns {gyro error [deg/s], accel error [m/s^2]}.
std::pair<Eigen::Vector3d, Eigen::Vector3d> deterministic_errors(const ImuTruth& truth,
                                                                 const ImuInputs& in);

}  // namespace calstand::sim
