#pragma once
// The exporters behind export_calibration(), one source file each. Private to the analysis
// library; the conventions of each are in docs/exports.md.

#include "exports/calibration_export.hpp"
#include "solver/calibration_record.hpp"

namespace calstand::analysis::exporting {

/// PX4 parameters as a QGroundControl .params file. `legacy`: the scale factors as
/// TC_G<i>_SCL_* and TC_A<i>_SCL_* (PX4 whose thermal compensation still has them) instead of
/// CAL_ACC<i>_*SCALE.
ExportResult export_px4(const solver::Calibration& calibration, const ExportOptions& options,
                        bool legacy);

/// ArduPilot's INS_TCAL<n>_*, INS_ACC*OFFS_*, INS_ACC*SCAL_*, INS_GYR*OFFS_* and the
/// calibration temperatures as a .param file (NAME,VALUE).
ExportResult export_ardupilot(const solver::Calibration& calibration, const ExportOptions& options);

/// OpenVINS' kalibr_imu_chain.yaml: imu0 with the noise densities and the intrinsics.
ExportResult export_openvins(const solver::Calibration& calibration, const ExportOptions& options);

/// One CSV row per parameter with the record's identity.
ExportResult export_csv(const solver::Calibration& calibration);

}  // namespace calstand::analysis::exporting
