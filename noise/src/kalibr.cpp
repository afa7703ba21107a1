// Export of noise figures as a Kalibr imu.yaml.
#include "noise/kalibr.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>

#include "core/error.hpp"
#include "noise/model_figures.hpp"
#include "noise/run_noise.hpp"

namespace calstand::solver {
namespace {

void check_figure(double value, const char* field) {
  if (!std::isfinite(value) || value < 0.0) {
    throw core::InputError(field, fmt::format("must be finite and non-negative, got {}", value));
  }
}

}  // namespace

KalibrImu kalibr_from_run_noise(const RunNoise& noise, const std::string& rostopic,
                                std::vector<std::string>* unresolved) {
  KalibrImu imu;
  imu.rostopic = rostopic;
  imu.update_rate_hz = noise.sample_rate_hz;
  constexpr double kRadPerDeg = std::numbers::pi / 180.0;
  // Largest over the axes; "resolved" when every axis of the sensor resolved the term.
  const auto worst = [&](bool gyro, const NoiseTerm NoiseTerms::*term, const char* field) {
    double v = 0.0;
    bool all = true;
    for (const ChannelNoise& c : noise.channels) {
      if (is_gyro(c.channel) != gyro) continue;
      v = std::max(v, (c.terms.*term).value);
      all = all && (c.terms.*term).resolved;
    }
    if (!all && unresolved) unresolved->emplace_back(field);
    return v;
  };
  imu.gyroscope_noise_density =
      worst(true, &NoiseTerms::random_walk, "gyroscope_noise_density") * kRadPerDeg;
  imu.gyroscope_random_walk =
      worst(true, &NoiseTerms::rate_random_walk, "gyroscope_random_walk") * kRadPerDeg;
  imu.accelerometer_noise_density =
      worst(false, &NoiseTerms::random_walk, "accelerometer_noise_density");
  imu.accelerometer_random_walk =
      worst(false, &NoiseTerms::rate_random_walk, "accelerometer_random_walk");
  return imu;
}

KalibrImu kalibr_from_noise_models(const RunNoise& noise,
                                   const std::vector<ChannelModelFigures>& models,
                                   const std::string& rostopic,
                                   std::vector<std::string>* unresolved) {
  std::vector<std::string> allan_unresolved;
  KalibrImu imu = kalibr_from_run_noise(noise, rostopic, &allan_unresolved);
  constexpr double kRadPerDeg = std::numbers::pi / 180.0;
  // The largest axis of the model's figure `name` when every axis of the sensor has it from its
  // model; none otherwise (one number per sensor: not a mix of estimators).
  const auto from_models = [&](bool gyro, const char* name) -> std::optional<double> {
    double v = 0.0;
    std::size_t axes = 0;
    for (const ChannelModelFigures& m : models) {
      if (is_gyro(m.channel) != gyro) continue;
      const auto f = std::find_if(m.figures.begin(), m.figures.end(),
                                  [&](const ModelFigure& x) { return x.name == name; });
      if (f == m.figures.end() || f->estimator != kGmwmEstimator) return std::nullopt;
      v = std::max(v, f->value);
      ++axes;
    }
    if (axes != 3) return std::nullopt;
    return v;
  };
  const auto use = [&](bool gyro, const char* name, const char* field, double& value,
                       std::string& estimator) {
    if (const auto v = from_models(gyro, name)) {
      value = *v * (gyro ? kRadPerDeg : 1.0);
      estimator = std::string(kGmwmEstimator);
    } else {
      estimator = std::string(kAllanLineEstimator);
      if (unresolved && std::find(allan_unresolved.begin(), allan_unresolved.end(), field) !=
                            allan_unresolved.end()) {
        unresolved->emplace_back(field);
      }
    }
  };
  use(true, "white_density", "gyroscope_noise_density", imu.gyroscope_noise_density,
      imu.gyroscope_noise_density_estimator);
  use(true, "random_walk", "gyroscope_random_walk", imu.gyroscope_random_walk,
      imu.gyroscope_random_walk_estimator);
  use(false, "white_density", "accelerometer_noise_density", imu.accelerometer_noise_density,
      imu.accelerometer_noise_density_estimator);
  use(false, "random_walk", "accelerometer_random_walk", imu.accelerometer_random_walk,
      imu.accelerometer_random_walk_estimator);
  return imu;
}

void KalibrImu::validate() const {
  if (rostopic.empty() || rostopic.find_first_of("\n\r") != std::string::npos) {
    throw core::InputError("rostopic", "must be one non-empty line");
  }
  if (!std::isfinite(update_rate_hz) || update_rate_hz <= 0.0) {
    throw core::InputError("update_rate",
                           fmt::format("must be positive and finite, got {}", update_rate_hz));
  }
  check_figure(accelerometer_noise_density, "accelerometer_noise_density");
  check_figure(accelerometer_random_walk, "accelerometer_random_walk");
  check_figure(gyroscope_noise_density, "gyroscope_noise_density");
  check_figure(gyroscope_random_walk, "gyroscope_random_walk");
}

std::string kalibr_yaml(const KalibrImu& imu) {
  imu.validate();
  // The topic is quoted so that YAML reads any name as a string.
  std::string topic;
  for (const char c : imu.rostopic) {
    if (c == '"' || c == '\\') topic += '\\';
    topic += c;
  }
  return fmt::format(
      "# IMU noise figures for Kalibr, from calstand's noise analysis of a record at rest.\n"
      "# Densities are the white-noise coefficients, random walks the bias random walks.\n"
      "# Each figure's estimator follows its unit: gmwm (the identified composite noise\n"
      "# model, calstand noise-id) or allan-line (lines fitted to the Allan variance).\n"
      "# Measured at rest; a moving platform may need larger values.\n"
      "accelerometer_noise_density: {:.6g}  # [m/s^2/sqrt(Hz)] estimator: {}\n"
      "accelerometer_random_walk: {:.6g}  # [m/s^3/sqrt(Hz)] estimator: {}\n"
      "gyroscope_noise_density: {:.6g}  # [rad/s/sqrt(Hz)] estimator: {}\n"
      "gyroscope_random_walk: {:.6g}  # [rad/s^2/sqrt(Hz)] estimator: {}\n"
      "rostopic: \"{}\"\n"
      "update_rate: {:.6g}  # [Hz]\n",
      imu.accelerometer_noise_density, imu.accelerometer_noise_density_estimator,
      imu.accelerometer_random_walk, imu.accelerometer_random_walk_estimator,
      imu.gyroscope_noise_density, imu.gyroscope_noise_density_estimator, imu.gyroscope_random_walk,
      imu.gyroscope_random_walk_estimator, topic, imu.update_rate_hz);
}

}  // namespace calstand::solver
