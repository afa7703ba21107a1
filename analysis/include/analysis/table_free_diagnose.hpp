#pragma once
// The diagnosis of a run without a table (`calstand diagnose`, POST /runs/{id}/diagnose): the
// model-against-measurement loop where no orientation is known. The table-free fit of the model
// as given shows where it fails (the poses whose |f| misses g, the turns after which the gyro
// points gravity the wrong way); each optional term the table-free methods can fit
// (table_free_model.hpp) is added in turn and ranked by how much of the residual it explains,
// judged against the residual's own scatter (an F-test), so that a wandering bias or a hand that
// moves, which no term explains, is not taken for a missing effect.

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "analysis/table_free_fit.hpp"
#include "store/database.hpp"

namespace calstand::analysis {

/// One optional term added to the model.
struct TableFreeCandidate {
  std::string term;    ///< e.g. "gyro_g_sensitivity"
  std::string sensor;  ///< "accel" or "gyro": whose fit it enters and is judged by
  int added_parameters = 0;
  double chi2_before = 0.0;  ///< that sensor's fit, against its noise model
  double chi2_after = 0.0;
  int dof_after = 0;
  double chi2_per_dof_before = 0.0;
  double chi2_per_dof_after = 0.0;
  /// F-test of the added parameters against the residual left after them: the chance that
  /// noise alone lowers chi2 this much (scale free: a noise model too optimistic by a constant
  /// factor does not make a term significant).
  double p_value = 1.0;
  /// BIC after - before with the residual variance profiled out, n ln(chi2_after /
  /// chi2_before) + k ln n (n residuals, k added parameters): negative favours the term.
  double delta_bic = 0.0;
  /// The residual the sensor's fit reports, before and after ("|f| - g rms 0.151 mg" or
  /// "gravity direction after the turns 0.53 deg rms").
  std::string residual_before;
  std::string residual_after;
  std::string effect;  ///< the catalogue's physical effect, in words
};

/// A pose or turn where the model fails most, in its noise's units.
struct TableFreeOutlier {
  std::string what;  ///< "pose 12" or "turn 11 -> 12"
  double start_s = 0.0;
  double end_s = 0.0;
  double residual = 0.0;  ///< mg (pose: |f| - g) or deg (turn: gravity direction)
  std::string unit;
  double z = 0.0;  ///< residual / its sigma from the noise
};

struct TableFreeDiagnosis {
  TableFreeFit fit;                            ///< the model as given
  std::vector<TableFreeOutlier> worst;         ///< largest |z| first
  std::vector<TableFreeCandidate> candidates;  ///< best (lowest delta BIC) first
  std::vector<std::string> untestable;         ///< "term: why" for terms not tried
  bool explained = false;   ///< the model, or the model with the best candidate, fits the noise
  std::string recommended;  ///< the term to add, or empty
  std::string advice;       ///< one paragraph for the user
};

/// Fits `request`'s model to `run` (table_free_fit(), recorded in the history as
/// `request.history_command`) and tries each optional term it lacks. Throws as
/// table_free_fit().
TableFreeDiagnosis diagnose_table_free(store::Database& db, std::int64_t run,
                                       const TableFreeFitRequest& request);

/// {"run", "device", "method", "model": [terms], "fit": to_json(TableFreeFit), "worst":
///  [{"what", "start_s", "end_s", "residual", "unit", "z"}], "candidates": [{"term", "sensor",
///  "added_parameters", "chi2_before", "chi2_after", "dof_after", "chi2_dof_before",
///  "chi2_dof_after", "p_value", "delta_bic", "residual_before", "residual_after",
///  "explanation"}], "untestable": [...], "explained", "recommended", "advice"} (the fields a
///  table diagnosis also has carry the same names)
nlohmann::json to_json(const TableFreeDiagnosis& diagnosis);

}  // namespace calstand::analysis
