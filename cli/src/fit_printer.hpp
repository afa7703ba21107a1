#pragma once
// Human output shared by `fit`, `calibrate` and `diagnose`.

#include <CLI/CLI.hpp>
#include <cstdint>
#include <string>
#include <vector>

#include "solver/fit.hpp"
#include "solver/groups.hpp"
#include "store/database.hpp"

namespace calstand::cli {

/// The model `fit` and `calibrate` use when none is given: the classical bias, scale factor and
/// misalignment of both triads, with the Earth rate in the reference.
inline constexpr const char* kDefaultModel =
    "gyro_bias,gyro_scale,gyro_misalignment,earth_rate,accel_bias,accel_scale,accel_misalignment";

solver::SensorRows parse_sensor_rows(const std::string& sensor);

/// What every command that fits a model to a run takes.
struct RunModelOptions {
  std::string db;
  std::int64_t run = 0;
  std::string model = kDefaultModel;
  std::vector<std::string> customs;
  std::string device;
  std::string sensor = "both";
};

/// Adds --db, --run, --model, --custom, --device and (when `with_sensor`) --sensor to `cmd`,
/// with the catalogue of terms as its help footer.
void add_run_model_options(CLI::App* cmd, RunModelOptions& opt, bool with_sensor = true);

/// The parameter table (value, sigma, unit), the parameters the run cannot determine, and the
/// fit quality against the noise floor.
void print_fit(const solver::FitResult& fit);

/// The noise model the fit's weights came from: per channel its white density and wander in
/// datasheet units, or why the wander was not determined.
void print_noise_model(const solver::FitResult& fit);

/// The groups of steps where the fit fails, worst first, and the worst single residuals.
void print_groups(const std::vector<solver::GroupQuality>& groups,
                  const std::vector<solver::WorstStep>& worst, std::size_t max_groups = 8);

/// Appends the fit to the run's history (calstand history).
void record_history(store::Database& db, std::int64_t run, const std::string& device,
                    const std::string& command, const solver::Model& model,
                    const solver::FitResult& fit, const std::string& sensors);

/// The catalogue of terms for --help.
std::string catalogue_help();

}  // namespace calstand::cli
