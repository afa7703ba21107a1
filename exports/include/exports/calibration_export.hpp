#pragma once
// A calibration record written in the form its consumer reads (calstand export-calibration):
// PX4 and ArduPilot parameter files, OpenVINS' kalibr_imu_chain.yaml, one CSV row per
// parameter. Each target's frames, units, polynomial variables and signs, and the formula from
// the record to each of its parameters, are in docs/exports.md.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "solver/calibration_record.hpp"

namespace calstand::analysis {

/// The formats export-calibration writes.
enum class ExportFormat {
  kPx4,        ///< PX4 (sensor_calibration library): TC_* offsets, CAL_ACC*_*SCALE, QGC .params
  kPx4Legacy,  ///< PX4 whose thermal compensation still has the TC_*_SCL_* scale factors
  kArduPilot,  ///< INS_TCAL*, INS_ACC*OFFS/SCAL, INS_GYR*OFFS as a .param file
  kOpenVins,   ///< OpenVINS' kalibr_imu_chain.yaml (imu0: noise, Tw, Ta, R_IMUto*, Tg)
  kCsv,        ///< one row per parameter with the unit's identity (RFC 4180)
};

/// One name --format takes. `kalibr` is another name of kOpenVins: the file OpenVINS reads as
/// kalibr_imu_chain.yaml with its "kalibr" IMU model.
struct ExportFormatInfo {
  std::string_view name;
  ExportFormat format;
  std::string_view description;  ///< what the file is, for --help
};

/// Every format name, in the order --help lists them.
const std::vector<ExportFormatInfo>& export_formats();

/// The format called `name`. Throws core::InputError naming --format and listing the names.
ExportFormat parse_export_format(std::string_view name);

/// The target's own settings that a record cannot know. Defaults give a file that loads, with a
/// warning for each setting the target needs from the user (a PX4 device id of 0).
struct ExportOptions {
  /// Sensor slot: PX4 TC_G<i>/TC_A<i>/CAL_GYRO<i>/CAL_ACC<i>, ArduPilot IMU <i + 1>
  /// (INS_TCAL<i+1>_*, INS_ACCOFFS for 0, INS_ACC2OFFS for 1, ...). 0..2.
  int instance = 0;
  /// PX4 device ids of the unit's gyro and accelerometer (TC_G<i>_ID, CAL_GYRO<i>_ID, ...): PX4
  /// applies a calibration only to the sensor whose id matches. 0 = unknown (warned). 0..2^32-1.
  std::int64_t px4_gyro_id = 0;
  std::int64_t px4_accel_id = 0;
  /// MAVLink system id in the first column of a .params file: QGroundControl refuses a file
  /// saved for another system id. 1..255.
  int mav_sysid = 1;
  /// OpenVINS: imu0's rostopic, and its update rate [Hz] (none: the record's noise sample rate).
  std::string rostopic = "/imu0";
  std::optional<double> update_rate_hz;

  /// Throws core::InputError naming the option (--instance, --px4-gyro-id, ...) when out of range.
  void validate() const;
};

/// A file's text and what it could not say.
struct ExportResult {
  std::string text;
  /// One sentence each: the record's parameters the target cannot represent (named), terms
  /// written as zero, settings the user must supply. Never empty when something was left out.
  std::vector<std::string> warnings;
};

/// `calibration` (solver::read_calibration) in `format`. Throws core::InputError when the record
/// cannot be written in that format at all (a temperature polynomial of order above 3 for PX4
/// or ArduPilot, named; OpenVINS without an update rate) or the options are invalid.
ExportResult export_calibration(const solver::Calibration& calibration, ExportFormat format,
                                const ExportOptions& options = {});

}  // namespace calstand::analysis
