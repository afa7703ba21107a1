#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "sim/imu_truth.hpp"

namespace calstand::sim {

/// Draws one IMU from a spec sheet (format calstand-spec/1, schemas/spec-sheet.schema.json):
/// every figure is read as a 1-sigma spread in the unit it is written in and converted with
/// core::convert. Calibratable errors (bias, scale factor, misalignment, g-sensitivity,
/// temperature coefficients, asymmetry, vibration sensitivity) are drawn once from N(0, figure)
/// with `seed`; noise figures become the noise processes:
///   random_walk / white_noise      -> white noise (ARW, VRW)
///   in_run_bias_stability          -> bias instability B = figure / 0.664 (the figure is the
///                                     Allan floor; kFlickerAllanFloorPerCoefficient)
///   bandwidth (gyro, accel)        -> that sensor's output low-pass filter
///   bias_variation {sigma, tau}    -> first-order Gauss-Markov
///   rate/acceleration random walk  -> random walk
///   bias_repeatability             -> turn-on bias (new at each power-up); also the spread of
///                                     the fixed bias when no `bias` figure is given
/// Throws core::SchemaError / core::InputError naming the file and field on bad input; a
/// negative figure (or a zero sample rate or correlation time) is an InputError naming the
/// sheet's field, e.g. `mine.json: gyro.random_walk: -0.07 deg/sqrt(h) must not be negative`.
ImuTruth truth_from_spec(const nlohmann::json& spec, const std::string& file_name,
                         std::uint64_t seed);

/// A spec sheet shipped with calstand, by name ("ln200", "adis16488"), or std::nullopt.
std::optional<nlohmann::json> builtin_spec(std::string_view name);
/// Names of the shipped spec sheets.
std::vector<std::string> builtin_spec_names();

/// Text of a data file shipped in sim/specs or sim/stations, compiled into the binary.
std::optional<std::string_view> builtin_file(std::string_view file_name);
std::vector<std::string_view> builtin_file_names();

}  // namespace calstand::sim
