#include "fit_printer.hpp"

#include <fmt/format.h>

#include <cmath>
#include <limits>

#include "core/error.hpp"
#include "core/error_terms.hpp"

namespace calstand::cli {

void add_run_model_options(CLI::App* cmd, RunModelOptions& opt, bool with_sensor) {
  cmd->add_option("--db", opt.db, "Database file")->required();
  cmd->add_option("--run", opt.run, "Run id")->required();
  cmd->add_option("--model", opt.model,
                  "Comma-separated terms of error-model.md (gyro_temp_bias:2 for order 2)")
      ->capture_default_str();
  cmd->add_option("--custom", opt.customs,
                  "A custom term NAME=SENSOR:EXPR (muParser; signals as in error-model.md), or "
                  "NAME=SENSOR.AXES:EXPR on some axes only (k=gyro.z:force_z^2); repeatable");
  cmd->add_option("--device", opt.device, "IMU (default: the run's only IMU)");
  if (with_sensor) {
    cmd->add_option("--sensor", opt.sensor, "Rows to fit: both, gyro or accel")
        ->check(CLI::IsMember({"both", "gyro", "accel"}))
        ->capture_default_str();
  }
  cmd->footer(catalogue_help());
}

void add_noise_run_option(CLI::App* cmd, std::optional<std::int64_t>& noise_run) {
  cmd->add_option("--noise-run", noise_run,
                  "A static run of the same unit (hours at rest, warmed up): its wander (estimated "
                  "from the means of its longest capture cut into this run's step length) weighs "
                  "the steps instead of one estimated from this run, so that a slow effect (a "
                  "warm-up) cannot pass for wander")
      ->check(CLI::PositiveNumber);
}

void print_fit(const solver::FitResult& fit) {
  fmt::print("model: {}\n\n", fit.model);
  fmt::print("{:<28} {:>15} {:>12}  {}\n", "parameter", "value", "sigma", "unit");
  for (const auto& p : fit.parameters) {
    fmt::print("{:<28} {:>15.6g} {:>12.3g}  {}\n", p.name, p.value, p.sigma, p.unit);
  }
  if (!fit.unidentifiable.empty()) {
    fmt::print("\nnot determined by this run (held at zero):\n");
    for (const auto& u : fit.unidentifiable) fmt::print("  {:<26} {}\n", u.name, u.reason);
  }
  fmt::print("\nfit quality: chi2/dof {:.3g} ({:.1f} over {} degrees of freedom)\n", fit.chi2_dof,
             fit.chi2, fit.dof);
  const bool gyro = fit.rows != solver::SensorRows::kAccel;
  const bool accel = fit.rows != solver::SensorRows::kGyro;
  if (gyro) {
    fmt::print(
        "  gyro  chi2/dof {:.3g}, step residual rms {:.3g} deg/s, noise of a step mean {:.3g} "
        "{:.3g} {:.3g} deg/s\n",
        fit.chi2_dof_gyro, fit.residual_rms_gyro_dps, fit.noise_floor[0], fit.noise_floor[1],
        fit.noise_floor[2]);
  }
  if (accel) {
    fmt::print(
        "  accel chi2/dof {:.3g}, step residual rms {:.3g} m/s^2, noise of a step mean {:.3g} "
        "{:.3g} {:.3g} m/s^2\n",
        fit.chi2_dof_accel, fit.residual_rms_accel_mps2, fit.noise_floor[3], fit.noise_floor[4],
        fit.noise_floor[5]);
  }
  print_noise_model(fit);
  const auto verdict = [&](const char* sensor, double chi2_dof, int dof) {
    if (!std::isfinite(chi2_dof)) return;
    // Weighed by the white noise alone (the run has too few steps to measure a wander on the
    // sensor), an excess may be the wander: it is not called a missing effect.
    const int first = sensor[0] == 'g' ? solver::kGx : solver::kAx;
    bool too_few_steps = false;
    for (int c = first; c < first + 3; ++c)
      too_few_steps =
          too_few_steps || fit.noise.channels[static_cast<std::size_t>(c)].too_few_steps;
    if (solver::above_noise(chi2_dof, dof) && too_few_steps) {
      fmt::print(
          "  {}: the residuals are {:.2g} times the white noise, more than chance gives over {} "
          "degrees of freedom: a missing effect or a wandering bias this run cannot measure "
          "(`calstand diagnose`, with a static run as --noise-run, tells them apart)\n",
          sensor, std::sqrt(chi2_dof), dof);
    } else if (solver::above_noise(chi2_dof, dof)) {
      fmt::print(
          "  {}: the residuals are {:.2g} times the noise, more than chance gives over {} "
          "degrees of freedom: the model misses an effect (try `calstand diagnose`)\n",
          sensor, std::sqrt(chi2_dof), dof);
    } else {
      fmt::print("  {}: the residuals are at the noise floor\n", sensor);
    }
  };
  if (gyro) verdict("gyro", fit.chi2_dof_gyro, fit.dof_gyro);
  if (accel) verdict("accel", fit.chi2_dof_accel, fit.dof_accel);
}

void print_noise_model(const solver::FitResult& fit) {
  fmt::print("\nnoise model: {}\n", fit.noise.method);
  const bool gyro = fit.rows != solver::SensorRows::kAccel;
  const bool accel = fit.rows != solver::SensorRows::kGyro;
  for (int c = 0; c < solver::kChannels; ++c) {
    if ((c < solver::kAx && !gyro) || (c >= solver::kAx && !accel)) continue;
    const auto& ch = fit.noise.channels[static_cast<std::size_t>(c)];
    // White density in datasheet units: deg/sqrt(h) for a gyro, ug/sqrt(Hz) for an accelerometer.
    const double density = fit.sample_rate_hz > 0.0
                               ? std::sqrt(fit.noise.white.density[c] / fit.sample_rate_hz)
                               : std::numeric_limits<double>::quiet_NaN();
    const std::string white =
        c < solver::kAx ? fmt::format("white {:.3g} deg/sqrt(h)", density * 60.0)
                        : fmt::format("white {:.3g} ug/sqrt(Hz)", density * 1e6 / 9.80665);
    fmt::print("  {}  {}; {}{}\n", solver::channel_name(c), white,
               ch.determined ? "" : "NOT DETERMINED: ", ch.note);
  }
}

void print_groups(const std::vector<solver::GroupQuality>& groups,
                  const std::vector<solver::WorstStep>& worst, std::size_t max_groups) {
  if (groups.empty()) return;
  fmt::print("\nwhere the model fails (step groups, worst first):\n");
  fmt::print("  {:<40} {:>10} {:>6}\n", "group", "chi2/dof", "steps");
  for (std::size_t i = 0; i < groups.size() && i < max_groups; ++i) {
    fmt::print("  {:<40} {:>10.3g} {:>6}\n", groups[i].group, groups[i].chi2_dof,
               groups[i].steps.size());
  }
  if (!worst.empty()) {
    fmt::print("worst steps:");
    for (std::size_t i = 0; i < worst.size() && i < 5; ++i) {
      fmt::print(" step {} {} z={:+.1f}{}", worst[i].step, worst[i].channel, worst[i].z,
                 i + 1 < std::min<std::size_t>(worst.size(), 5) ? ";" : "\n");
    }
  }
}

std::string catalogue_help() {
  std::string text = "Error terms (error-model.md):\n";
  for (const auto& t : core::error_term_catalogue()) {
    text += fmt::format("  {:<22} [{}] {}\n",
                        std::string(t.name) + (t.polynomial_order ? "[:N]" : ""), t.unit, t.effect);
  }
  return text;
}

}  // namespace calstand::cli
