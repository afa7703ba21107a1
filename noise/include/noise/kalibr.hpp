#pragma once

#include <string>
#include <vector>

namespace calstand::solver {

/// The noise figures of a Kalibr IMU configuration (imu.yaml), in Kalibr's units. Kalibr's
/// "noise density" is the white-noise coefficient N of the IEEE model and its "random walk" is
/// the rate random walk K (the continuous-time bias random walk), both one number per sensor.
struct KalibrImu {
  std::string rostopic = "/imu0";
  double update_rate_hz = 0.0;
  double accelerometer_noise_density = 0.0;  ///< [m/s^2/sqrt(Hz)]
  double accelerometer_random_walk = 0.0;    ///< [m/s^3/sqrt(Hz)]
  double gyroscope_noise_density = 0.0;      ///< [rad/s/sqrt(Hz)]
  double gyroscope_random_walk = 0.0;        ///< [rad/s^2/sqrt(Hz)]
  /// Which estimator gave each figure (model_figures.hpp: "gmwm", the identified composite
  /// model's white or random-walk term; "allan-line", lines fitted to the Allan variance),
  /// written in the figure's comment.
  std::string accelerometer_noise_density_estimator = "allan-line";
  std::string accelerometer_random_walk_estimator = "allan-line";
  std::string gyroscope_noise_density_estimator = "allan-line";
  std::string gyroscope_random_walk_estimator = "allan-line";

  /// Throws core::InputError naming the field for a negative or non-finite figure, a
  /// non-positive update rate or an empty or multi-line topic.
  void validate() const;
};

struct RunNoise;
struct ChannelModelFigures;

/// Kalibr figures from a run's noise analysis: per sensor the largest of its three axes (Kalibr
/// takes one number; the worst axis keeps the filter honest on every axis), gyro figures
/// converted from deg to rad, update_rate the measured sample rate. A term the fit did not
/// resolve is written as 0, which Kalibr cannot use: `unresolved` (when given) receives the
/// names of such fields so the caller can warn.
KalibrImu kalibr_from_run_noise(const RunNoise& noise, const std::string& rostopic = "/imu0",
                                std::vector<std::string>* unresolved = nullptr);

/// As kalibr_from_run_noise(), each figure from the identified models `models` (per channel, as
/// channel_noise_models() gives them) where every axis of the sensor has it from its model
/// ("gmwm": the white density N, the random walk K), else from the Allan line as
/// kalibr_from_run_noise() (the estimator fields say which). `unresolved` receives a field only
/// when its Allan-line figure is used and not resolved on every axis.
KalibrImu kalibr_from_noise_models(const RunNoise& noise,
                                   const std::vector<ChannelModelFigures>& models,
                                   const std::string& rostopic = "/imu0",
                                   std::vector<std::string>* unresolved = nullptr);

/// The imu.yaml text Kalibr reads, with the units in comments. Figures are written with 6
/// significant digits. Throws as KalibrImu::validate().
std::string kalibr_yaml(const KalibrImu& imu);

}  // namespace calstand::solver
