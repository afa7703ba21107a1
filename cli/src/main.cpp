// calstand: the command line of the calstand IMU test and calibration station.
#include <CLI/CLI.hpp>
#include <exception>
#include <iostream>
#include <string>

#include "commands.hpp"
#include "core/error.hpp"
#include "core/version.hpp"
#include "help_layout.hpp"

int main(int argc, char** argv) {
  CLI::App app{"calstand: IMU test and calibration on a dual-axis rate table with a chamber"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("calstand ") + calstand::core::kVersion);
  calstand::cli::register_accept(app);
  calstand::cli::register_allan(app);
  calstand::cli::register_analyze(app);
  calstand::cli::register_calibrate(app);
  calstand::cli::register_calibrations(app);
  calstand::cli::register_certificate(app);
  calstand::cli::register_client(app);
  calstand::cli::register_client_watch(app);
  calstand::cli::register_demo(app);
  calstand::cli::register_device(app);
  calstand::cli::register_diagnose(app);
  calstand::cli::register_export_calibration(app);
  calstand::cli::register_fit(app);
  calstand::cli::register_fleet(app);
  calstand::cli::register_lot(app);
  calstand::cli::register_import_export(app);
  calstand::cli::register_noise_study(app);
  calstand::cli::register_plan(app);
  calstand::cli::register_report(app);
  calstand::cli::register_run(app);
  calstand::cli::register_runs(app);
  calstand::cli::register_sim_session(app);
  calstand::cli::register_sim_station(app);
  calstand::cli::register_station(app);
  calstand::cli::register_sync(app);
  calstand::cli::register_token(app);
  calstand::cli::register_trend(app);
  calstand::cli::register_truth_from_spec(app);
  calstand::cli::register_units(app);
  calstand::cli::arrange_help(app);  // after every register_x: groups by task, examples
  try {
    app.parse(argc, argv);
  } catch (const CLI::RuntimeError& e) {
    return e.get_exit_code();  // a command that already reported its outcome
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const calstand::core::InputError& e) {
    std::cerr << "calstand: error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "calstand: error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
