#pragma once
// Human output shared by `fit`, `calibrate` and `diagnose`.

#include <string>

#include "solver/fit.hpp"

namespace calstand::cli {

/// The model `fit` and `calibrate` use when none is given: the classical bias, scale factor and
/// misalignment of both triads, with the Earth rate in the reference.
inline constexpr const char* kDefaultModel =
    "gyro_bias,gyro_scale,gyro_misalignment,earth_rate,accel_bias,accel_scale,accel_misalignment";

solver::SensorRows parse_sensor_rows(const std::string& sensor);

/// The parameter table (value, sigma, unit), the parameters the run cannot determine, and the
/// fit quality against the noise floor.
void print_fit(const solver::FitResult& fit);

/// The catalogue of terms for --help.
std::string catalogue_help();

}  // namespace calstand::cli
