#pragma once
// `calstand accept` and POST /runs/{id}/acceptance as one library call: the newest record of
// each unit of a run judged against a specification, with the unit's drift from its record in
// force and, when asked, the validation run; the verdicts stored with their records.

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "factory/acceptance.hpp"
#include "factory/acceptance_spec.hpp"
#include "store/database.hpp"

namespace calstand::analysis {

/// The run (or the device asked for) has no calibration record to judge (HTTP 409).
class NoCalibrationRecord : public core::InputError {
 public:
  using core::InputError::InputError;
};

/// What to judge.
struct AcceptRequest {
  std::int64_t run = 0;
  std::string device;  ///< "" = every unit of the run that has a record
  /// The run measured again with the records applied (the specification's validation part);
  /// none: a specification with a validation part fails its validation checks.
  std::optional<std::int64_t> validation_run;
};

/// Every unit judged.
struct AcceptanceOutcome {
  std::int64_t run = 0;
  AcceptanceSpec spec;
  std::optional<std::int64_t> validation_run;
  std::vector<UnitAcceptance> units;  ///< in the order of the units' slots (imu0, imu1, ...)
  Verdict verdict = Verdict::kFail;   ///< of all units together (combine())
};

/// Judges the newest calibration record of each unit of `request.run` (or of
/// `request.device`) against `spec`: its checks, its unit verdict, its as-found drift, and
/// the validation checks. Writes nothing but the validation run's corrected copy and its fit
/// history. Throws RunNotFound for an unknown run, NoCalibrationRecord naming the run when it
/// has no record (or none of `request.device`), and as fit_validation_run().
AcceptanceOutcome accept_run(store::Database& db, const AcceptanceSpec& spec,
                             const AcceptRequest& request);

/// Stores each unit's verdict with its record (store::insert_acceptance: the specification's
/// name and sha256, the unit's JSON) and sets the units' acceptance_id.
void store_acceptances(store::Database& db, AcceptanceOutcome& outcome);

/// {"run", "spec": {"name", "file", "sha256", "k"}, "k", "decision_rule", "validation_run",
/// "verdict", "units": [unit JSON, acceptance.hpp]}, each unit with "acceptance_id" once
/// stored.
nlohmann::json to_json(const AcceptanceOutcome& outcome);

}  // namespace calstand::analysis
