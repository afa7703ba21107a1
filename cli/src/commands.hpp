#pragma once

#include <CLI/CLI.hpp>

namespace calstand::cli {

// Each subcommand lives in its own cmd_<name>.cpp and registers itself here. A command's
// callback returns through CLI11; errors are reported as one line on stderr with exit code 2
// (bad input) or 1 (failure), see main.cpp.
void register_accept(CLI::App& app);  // acceptance against a specification
void register_allan(CLI::App& app);   // allan and noise
void register_analyze(CLI::App& app);
void register_calibrate(CLI::App& app);  // calibrate and apply
void register_calibrations(CLI::App& app);
void register_certificate(CLI::App& app);
void register_client(CLI::App& app);  // calstandd clients: submit, status, pause, resume, abort
void register_client_watch(CLI::App& app);  // calstandd client: watch
void register_demo(CLI::App& app);
void register_device(CLI::App& app);
void register_diagnose(CLI::App& app);  // diagnose and history
void register_export_calibration(CLI::App& app);
void register_fit(CLI::App& app);
void register_fleet(CLI::App& app);  // the central database: migrate, runs, units, calibrations
void register_lot(CLI::App& app);
void register_import_export(CLI::App& app);  // import and export
void register_noise_study(CLI::App& app);
void register_plan(CLI::App& app);
void register_report(CLI::App& app);
void register_run(CLI::App& app);
void register_runs(CLI::App& app);         // runs and show
void register_sim_session(CLI::App& app);  // hand-held / Ferraris sessions, no table
void register_sim_station(CLI::App& app);
void register_station(CLI::App& app);
void register_sync(CLI::App& app);   // a station's database to the central one
void register_token(CLI::App& app);  // calstandd's named tokens, hashed: add, list, remove
void register_trend(CLI::App& app);
void register_truth_from_spec(CLI::App& app);
void register_units(CLI::App& app);

}  // namespace calstand::cli
