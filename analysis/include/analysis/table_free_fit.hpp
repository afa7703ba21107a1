#pragma once
// The calibration of a run recorded without a table (an imported calstand-import/2 folder
// without `table`): the orientation of no sample is known, so the classical fit cannot run.
// Labelled Ferraris sessions (six holds and three turns) go to solver::calibrate_ferraris();
// anything else to the static-interval detector, the gravity norm for the accelerometers and
// the integration between static poses for the gyros. `calstand fit`, `calstand show` and the
// daemon's POST /runs/{id}/fits call these for such a run.

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "solver/ferraris.hpp"
#include "solver/gravity_norm.hpp"
#include "solver/gyro_integration.hpp"
#include "solver/static_detector.hpp"
#include "store/database.hpp"

namespace calstand::analysis {

/// How to find the static poses and what to fit.
struct TableFreeFitRequest {
  std::string device;  ///< "" = the run's only IMU
  solver::StaticDetectorOptions detector;
  /// Static intervals given by the operator [s of station time], in time order; the first is
  /// the initial rest. Empty: the detector finds them.
  std::vector<std::pair<double, double>> intervals_s;
  /// Also fit the gyros' g-sensitivity (imucal's K_ga) in the integration method.
  bool gyro_g_sensitivity = false;
};

/// The static poses of a table-free run: what the detector found, or the operator's intervals.
struct TableFreePoses {
  std::int64_t run = 0;
  std::string device;
  std::vector<core::ImuSample> samples;  ///< every sample of the run, in time order
  solver::StaticDetection detection;     ///< intervals index into `samples`
  bool given = false;                    ///< the intervals were given, not detected
};

/// What a table-free fit found: "ferraris" (labelled sections) or "gravity_norm" (accel by the
/// gravity norm, gyro by integration between poses).
struct TableFreeFit {
  std::int64_t run = 0;
  std::string device;
  std::string method;
  double gravity_mps2 = 0.0;
  std::optional<TableFreePoses> poses;  ///< gravity_norm
  std::optional<solver::GravityNormResult> accel;
  std::optional<solver::GyroIntegrationResult> gyro;
  std::optional<solver::FerrarisResult> ferraris;
};

/// True when `run` has no known orientation and needs these methods (store::orientation_known).
bool needs_table_free_fit(store::Database& db, std::int64_t run);

/// The static poses of `run` (detected, or as `request.intervals_s` gives them). Throws
/// RunNotFound, NothingToFit, or core::InputError naming what is wrong (a run with a known
/// orientation, a recording that does not start at rest, an interval outside the recording).
TableFreePoses table_free_poses(store::Database& db, std::int64_t run,
                                const TableFreeFitRequest& request);

/// Calibrates `run`: Ferraris when steps are labelled sections (the import's `sections`),
/// else the gravity norm and the integration between the poses. Throws as table_free_poses()
/// and as the solver does (fewer than 9 poses, a missing section), naming why.
TableFreeFit table_free_fit(store::Database& db, std::int64_t run,
                            const TableFreeFitRequest& request);

/// {"run", "device", "method", "gravity_mps2", "frame", "detection": {...} (gravity_norm),
///  "accel": {...}, "gyro": {...} (the solver's JSON of each) | "ferraris": {...}}.
nlohmann::json to_json(const TableFreeFit& fit);
/// {"run", "device", "given", "detection": solver::static_detection_to_json()}.
nlohmann::json to_json(const TableFreePoses& poses);

}  // namespace calstand::analysis
