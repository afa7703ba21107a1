#pragma once
// Human output shared by `fit`, `calibrate` and `diagnose`.

#include <CLI/CLI.hpp>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "analysis/run_model.hpp"
#include "solver/fit.hpp"
#include "solver/groups.hpp"

namespace calstand::cli {

/// What every command that fits a model to a run takes.
struct RunModelOptions {
  std::string db;
  std::int64_t run = 0;
  std::string model = analysis::kDefaultModel;
  std::vector<std::string> customs;
  std::string device;
  std::string sensor = "both";
};

/// Adds --db, --run, --model, --custom, --device and (when `with_sensor`) --sensor to `cmd`,
/// with the catalogue of terms as its help footer.
void add_run_model_options(CLI::App* cmd, RunModelOptions& opt, bool with_sensor = true);

/// Adds --noise-run ID: the wander measured on a static run of the same unit
/// (analysis/noise_run.hpp) instead of one estimated from the run itself.
void add_noise_run_option(CLI::App* cmd, std::optional<std::int64_t>& noise_run);

/// The parameter table (value, sigma, unit), the parameters the run cannot determine, and the
/// fit quality against the noise floor.
void print_fit(const solver::FitResult& fit);

/// The noise model the fit's weights came from: per channel its white density and wander in
/// datasheet units, or why the wander was not determined.
void print_noise_model(const solver::FitResult& fit);

/// The groups of steps where the fit fails, worst first, and the worst single residuals.
void print_groups(const std::vector<solver::GroupQuality>& groups,
                  const std::vector<solver::WorstStep>& worst, std::size_t max_groups = 8);

/// The catalogue of terms for --help.
std::string catalogue_help();

}  // namespace calstand::cli
