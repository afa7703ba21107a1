// `calstand export-calibration`: a calibration record written in the form its consumer reads
// (analysis/calibration_export.hpp; conventions in docs/exports.md).
#include <fmt/format.h>

#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "commands.hpp"
#include "core/file_output.hpp"
#include "core/json_schema.hpp"
#include "exports/calibration_export.hpp"
#include "solver/calibration_record.hpp"

namespace calstand::cli {
namespace {

struct ExportCalibrationOptions {
  std::string record;
  std::string format;
  std::string out;
  analysis::ExportOptions settings;
  double update_rate_hz = 0.0;
  CLI::Option* update_rate = nullptr;  ///< given or not (any value given is checked)
};

void run_export_calibration(const ExportCalibrationOptions& opt) {
  // Everything is checked before anything is written: the format, the options, the record.
  const analysis::ExportFormat format = analysis::parse_export_format(opt.format);
  analysis::ExportOptions settings = opt.settings;
  if (opt.update_rate->count() > 0) settings.update_rate_hz = opt.update_rate_hz;
  settings.validate();
  const solver::Calibration calibration =
      solver::read_calibration(core::read_json_file(opt.record), opt.record);
  const analysis::ExportResult result = analysis::export_calibration(calibration, format, settings);
  core::write_file_whole(opt.out, result.text);
  for (const std::string& w : result.warnings) {
    std::cerr << fmt::format("calstand: warning: {}\n", w);
  }
  fmt::print("{} written to {} ({} warning{})\n", opt.format, opt.out, result.warnings.size(),
             result.warnings.size() == 1 ? "" : "s");
}

}  // namespace

void register_export_calibration(CLI::App& app) {
  auto opt = std::make_shared<ExportCalibrationOptions>();
  std::string formats;
  for (const auto& f : analysis::export_formats()) {
    formats += fmt::format("\n  {}: {}", f.name, f.description);
  }
  auto* cmd = app.add_subcommand(
      "export-calibration",
      "Write a calibration record as the file its consumer reads (PX4, ArduPilot, OpenVINS, "
      "CSV); what the target cannot hold is named on stderr");
  cmd->add_option("--record", opt->record, "Calibration record (calstand calibrate's JSON)")
      ->required();
  cmd->add_option("--format", opt->format, "Target format:" + formats)->required();
  cmd->add_option("--out", opt->out, "File to write (replaced whole, or left untouched)")
      ->required();
  cmd->add_option("--instance", opt->settings.instance,
                  "Sensor slot: PX4 TC_G<N>/CAL_ACC<N>, ArduPilot IMU N+1 (0..2)")
      ->capture_default_str();
  cmd->add_option("--px4-gyro-id", opt->settings.px4_gyro_id,
                  "PX4 device id of the unit's gyro (TC_G<N>_ID, CAL_GYRO<N>_ID)");
  cmd->add_option("--px4-accel-id", opt->settings.px4_accel_id,
                  "PX4 device id of the unit's accelerometer (TC_A<N>_ID, CAL_ACC<N>_ID)");
  cmd->add_option("--sysid", opt->settings.mav_sysid,
                  "MAVLink system id of the vehicle (first column of a PX4 .params file)")
      ->capture_default_str();
  cmd->add_option("--rostopic", opt->settings.rostopic, "OpenVINS: imu0's topic")
      ->capture_default_str();
  opt->update_rate =
      cmd->add_option("--update-rate", opt->update_rate_hz,
                      "OpenVINS: the IMU's rate in Hz (default: the record's noise sample rate)");
  cmd->callback([opt] { run_export_calibration(*opt); });
}

}  // namespace calstand::cli
