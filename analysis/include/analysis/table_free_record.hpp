#pragma once
// The calibration record of a run without a table (`calstand calibrate` on such a run): the
// table-free fit's parameters in the record format `calstand apply` and the station's users read
// (schemas/calibration.schema.json), with the method, the frame convention and the fit quality
// of that method (|f| - g, the gravity direction after the turns) in place of step residuals.

#include <nlohmann/json.hpp>

#include "analysis/table_free_fit.hpp"
#include "store/database.hpp"

namespace calstand::analysis {

/// The record of `fit` (a fit of a run of `db`): "method" and "frame" say how it was obtained;
/// parameters the poses did not determine are listed as unidentifiable (not applied); the three
/// accelerometer misalignments fixed by the frame convention are given as 0 with sigma 0.
/// `valid_temperature_c` is the samples' range, null when the recording has no temperature.
/// Checked against the schema by the caller (calibrate_run()).
nlohmann::json table_free_calibration_record(store::Database& db, const TableFreeFit& fit);

}  // namespace calstand::analysis
