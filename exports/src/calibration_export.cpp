// export_calibration(): the format list and the dispatch to one exporter per file
// (export_px4.cpp, export_ardupilot.cpp, export_openvins.cpp, export_csv.cpp).
#include "exports/calibration_export.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <system_error>

#include "core/error.hpp"
#include "export_formats.hpp"

namespace calstand::analysis {

const std::vector<ExportFormatInfo>& export_formats() {
  static const std::vector<ExportFormatInfo> formats = {
      {"px4", ExportFormat::kPx4,
       "PX4 thermal compensation (TC_*) and CAL_* offsets and accel scales, QGroundControl "
       ".params"},
      {"px4-legacy", ExportFormat::kPx4Legacy,
       "PX4 whose thermal compensation has TC_*_SCL_* scale factors, QGroundControl .params"},
      {"ardupilot", ExportFormat::kArduPilot,
       "ArduPilot INS_TCAL*, INS_ACC*OFFS/SCAL, INS_GYR*OFFS, .param (NAME,VALUE)"},
      {"openvins", ExportFormat::kOpenVins,
       "OpenVINS kalibr_imu_chain.yaml: imu0 noise densities, Tw, Ta, R_IMUtoGYRO, R_IMUtoACC, "
       "Tg"},
      {"kalibr", ExportFormat::kOpenVins, "the same as openvins (OpenVINS' \"kalibr\" model)"},
      {"csv", ExportFormat::kCsv, "one row per parameter with the unit's identity"},
  };
  return formats;
}

ExportFormat parse_export_format(std::string_view name) {
  std::string names;
  for (const auto& f : export_formats()) {
    if (f.name == name) return f.format;
    names += (names.empty() ? "" : ", ") + std::string(f.name);
  }
  throw core::InputError("--format", fmt::format("unknown format \"{}\" (one of {})", name, names));
}

void ExportOptions::validate() const {
  if (instance < 0 || instance > 2) {
    throw core::InputError("--instance", fmt::format("must be 0, 1 or 2, got {}", instance));
  }
  constexpr std::int64_t kMaxDeviceId = 0xFFFFFFFFLL;  // PX4 device ids are 32-bit
  for (const auto& [id, option] :
       {std::pair{px4_gyro_id, "--px4-gyro-id"}, std::pair{px4_accel_id, "--px4-accel-id"}}) {
    if (id < 0 || id > kMaxDeviceId) {
      throw core::InputError(option, fmt::format("must be 0..{}, got {}", kMaxDeviceId, id));
    }
  }
  if (mav_sysid < 1 || mav_sysid > 255) {
    throw core::InputError("--sysid", fmt::format("must be 1..255, got {}", mav_sysid));
  }
  if (rostopic.empty() || rostopic.find_first_of("\r\n") != std::string::npos) {
    throw core::InputError("--rostopic", "must be one non-empty line");
  }
  if (update_rate_hz && !(std::isfinite(*update_rate_hz) && *update_rate_hz > 0.0)) {
    throw core::InputError("--update-rate",
                           fmt::format("must be positive and finite, got {}", *update_rate_hz));
  }
}

ExportResult export_calibration(const solver::Calibration& calibration, ExportFormat format,
                                const ExportOptions& options) {
  options.validate();
  switch (format) {
    case ExportFormat::kPx4:
      return exporting::export_px4(calibration, options, false);
    case ExportFormat::kPx4Legacy:
      return exporting::export_px4(calibration, options, true);
    case ExportFormat::kArduPilot:
      return exporting::export_ardupilot(calibration, options);
    case ExportFormat::kOpenVins:
      return exporting::export_openvins(calibration, options);
    case ExportFormat::kCsv:
      return exporting::export_csv(calibration);
  }
  throw core::InputError("--format", "unknown format");
}

}  // namespace calstand::analysis
