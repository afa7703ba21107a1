#pragma once
// The calibration of a run recorded without a table (an imported calstand-import/2 folder
// without `table`): the orientation of no sample is known, so the classical fit cannot run.
// Labelled Ferraris sessions (six holds and three turns) go to solver::calibrate_ferraris();
// anything else to the static-interval detector, the gravity norm for the accelerometers and
// the integration between static poses for the gyros. `calstand fit`, `calstand show` and the
// daemon's POST /runs/{id}/fits call these for such a run.

#include <cstdint>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "analysis/table_free_model.hpp"
#include "core/site.hpp"
#include "store/database.hpp"
#include "store/fit_history.hpp"
#include "tablefree/ferraris.hpp"
#include "tablefree/gravity_norm.hpp"
#include "tablefree/gyro_integration.hpp"
#include "tablefree/static_detector.hpp"

namespace calstand::analysis {

/// One mg in m/s^2: |f| - g is reported in mg, with 1 mg = 1e-3 standard gravity.
inline constexpr double kMgInMps2 = 1e-3 * core::kStandardGravity;

/// How to find the static poses and what to fit.
struct TableFreeFitRequest {
  std::string device;  ///< "" = the run's only IMU
  solver::StaticDetectorOptions detector;
  /// Static intervals given by the operator [s of station time], in time order; the first is
  /// the initial rest. Empty: the detector finds them.
  std::vector<std::pair<double, double>> intervals_s;
  /// The optional terms to fit (table_free_model.hpp); the Ferraris method takes none.
  TableFreeTerms terms;
  /// Model the Earth rate in the integration between poses (the model holds `earth_rate`, as
  /// the default one does), from the run's site latitude; a run without one is fitted without
  /// it and says so in the notes.
  bool earth_rate = true;
  /// What the model as given left out, and why (table_free_model()); copied to the fit.
  std::vector<std::string> notes;
  /// The command recorded in the run's fit history ("fit", "diagnose", "calibrate"); empty:
  /// not recorded.
  std::string history_command;
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
  TableFreeTerms terms;                    ///< the optional terms fitted
  bool earth_rate = true;                  ///< asked for (TableFreeFitRequest::earth_rate)
  std::optional<double> latitude_deg;      ///< the run's site latitude, when it has one
  std::vector<std::string> notes;          ///< what the model as given left out, and why
  std::optional<std::int64_t> history_id;  ///< the history row written, if any
  /// Range of the samples' temperatures [degC]; NaN when the recording has none.
  double min_temperature_c = std::numeric_limits<double>::quiet_NaN();
  double max_temperature_c = std::numeric_limits<double>::quiet_NaN();
  std::optional<TableFreePoses> poses;  ///< gravity_norm
  std::optional<solver::GravityNormResult> accel;
  std::optional<solver::GyroIntegrationResult> gyro;
  std::optional<solver::FerrarisResult> ferraris;
};

/// `fit` (gravity norm) again with other optional terms, on the same samples and static poses,
/// the poses' accel means referred to their ends as `fit` referred them (so the candidate's
/// chi2 is on the same data and weights as its base's): no database read, no detection,
/// nothing recorded (a diagnosis tries each candidate so).
/// Throws core::InputError (where "model") for a Ferraris fit, which takes no optional term.
TableFreeFit refit_table_free(const TableFreeFit& fit, const TableFreeTerms& terms);

/// A table-free fit's quality in a few numbers, both sensors together (the fit history's row
/// and the calibration record's `fit`).
struct TableFreeQuality {
  /// The accelerometers against their white noise alone (each fit estimates its own pose
  /// noise model, against which it is near 1), the gyros against their turns' noise model
  /// (gyro_integration.hpp: from the rest, the poses and the accel fit).
  double chi2 = 0.0;
  int dof = 0;
  double chi2_per_dof = 0.0;
  int parameters = 0;                           ///< estimated (not held, not fixed by convention)
  double rms_norm_residual_mps2 = 0.0;          ///< |calibrated f| - g over the poses or holds
  std::optional<double> rms_turn_residual_deg;  ///< gravity direction after each turn
  /// The accelerometers' chi2/dof against the noise model they were weighed with (gravity
  /// norm: a wandering bias shared by the pose means, estimated by REML).
  std::optional<double> accel_chi2_per_dof_noise_model;
};
TableFreeQuality table_free_quality(const TableFreeFit& fit);

/// The fit history's row of `fit` (model: table_free_model_text(); rms_accel_mps2: |f| - g;
/// rms_turn_deg: the gravity direction after each turn; no rms_gyro_dps: there are no rate
/// steps).
store::FitRecord table_free_history_record(const TableFreeFit& fit, const std::string& command);

/// Every parameter of the fit (accel, then gyro), each with its status.
std::vector<solver::TriadEstimate> table_free_parameters(const TableFreeFit& fit);

/// `poses` with the terms and notes of `model` read by table_free_model() (which throws
/// core::InputError naming a term such a run cannot fit).
TableFreeFitRequest table_free_request(const solver::Model& model, TableFreeFitRequest poses);

/// True when `run` has no known orientation and needs these methods (store::orientation_known).
bool needs_table_free_fit(store::Database& db, std::int64_t run);

/// The static poses of `run` (detected, or as `request.intervals_s` gives them). Throws
/// RunNotFound, NothingToFit, or core::InputError naming what is wrong (a run with a known
/// orientation, a recording that does not start at rest, an interval outside the recording).
TableFreePoses table_free_poses(store::Database& db, std::int64_t run,
                                const TableFreeFitRequest& request);

/// Calibrates `run`: Ferraris when steps are labelled sections (the import's `sections`),
/// else the gravity norm and the integration between the poses, and records the fit in the
/// run's history when `request.history_command` is set. Throws as table_free_poses() and as the
/// solver does (fewer than 9 poses, a missing section), naming why; core::InputError (where
/// "model") when the Ferraris method is asked for optional terms.
TableFreeFit table_free_fit(store::Database& db, std::int64_t run,
                            const TableFreeFitRequest& request);

/// {"run", "device", "method", "model": [terms], "notes", "gravity_mps2", "frame",
///  "chi2_dof" (null without redundancy), "dof", "parameters": [{"name", "value", "sigma",
///  "unit", "status"}] (accel then gyro), "unidentifiable": [{"name", "reason"}],
///  "quality": {"chi2", "dof", "chi2_per_dof", "parameters", "rms_norm_residual_mps2",
///  "rms_turn_residual_deg"}, "history_id" (when recorded), "poses": {...} (gravity_norm),
///  "accel": {...}, "gyro": {...} (the solver's JSON of each) | "ferraris": {...}}.
nlohmann::json to_json(const TableFreeFit& fit);
/// {"run", "device", "given", "detection": solver::static_detection_to_json()}.
nlohmann::json to_json(const TableFreePoses& poses);

}  // namespace calstand::analysis
