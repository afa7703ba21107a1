#pragma once
// A calibration record judged against an acceptance specification: one check per name each
// limit matches, each judged by the decision rule (decision_rule.hpp), and the unit's verdict.
// Pure: no database, so a record file can be judged as well as a stored one.

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "factory/acceptance_spec.hpp"
#include "factory/as_found.hpp"
#include "factory/decision_rule.hpp"

namespace calstand::analysis {

/// Where a check's value comes from.
enum class CheckSource {
  kRecord,      ///< the calibration record
  kValidation,  ///< the fit of the validation run corrected with the record
};

/// One limit applied to one value.
struct AcceptanceCheck {
  std::string check;  ///< e.g. "gyro_bias.x", "gyro_bias.x sigma", "chi2_dof", or the pattern
  /// "parameter", "sigma" (of a parameter), "noise", "fit" or "temperature".
  std::string kind;
  CheckSource source = CheckSource::kRecord;
  std::string spec_limit;       ///< the limit's place in the specification, e.g. "limits[0]"
  std::optional<double> value;  ///< none: not in the record
  std::optional<double> sigma;  ///< the guard band's sigma (0 when the record gives none)
  Bounds limit;
  std::string unit;
  Verdict verdict = Verdict::kFail;
  std::string reason;
};

/// The checks of `record` (schemas/calibration.schema.json, or the same shape built from a
/// validation fit) against `limits` with coverage factor `k`, in the order of the limits and
/// of the names in the record. A pattern that matches nothing the record holds is one failed
/// check "not in the record"; a parameter the record names as not determined fails with its
/// reason.
std::vector<AcceptanceCheck> judge_limits(const nlohmann::json& record,
                                          const std::vector<AcceptanceLimit>& limits, double k,
                                          CheckSource source);

/// The checks of the specification's `limits` on `record` (not its validation part).
std::vector<AcceptanceCheck> judge_record(const nlohmann::json& record, const AcceptanceSpec& spec);

/// A check as JSON: {"check", "kind", "source", "spec_limit", "value", "sigma", "limit",
/// "limit_kind", "limit_text", "unit", "verdict", "reason"}: value and sigma null when not in
/// the record; limit the bound (limit_json()), limit_kind which bound ("max_abs", "max",
/// "min", "min_max"), limit_text the zone in words ("|v| <= 0.005 deg/s").
nlohmann::json to_json(const AcceptanceCheck& check);

/// The verdict of a unit over its checks (decision_rule.hpp combine()).
Verdict unit_verdict(const std::vector<AcceptanceCheck>& checks);

/// The validation run of a unit: which run, corrected as which new run.
struct ValidationRun {
  std::int64_t run = 0;            ///< the run measured with the record applied
  std::int64_t corrected_run = 0;  ///< run corrected with the record (apply)
  std::string model;               ///< the terms fitted to the corrected run
};

/// One unit's judgement.
struct UnitAcceptance {
  std::string device;  ///< the IMU slot, e.g. imu0
  std::string serial;  ///< "" when unknown
  std::string model;   ///< the unit's model; "" when unknown
  std::int64_t calibration = 0;
  std::int64_t run = 0;
  Verdict verdict = Verdict::kFail;
  std::vector<AcceptanceCheck> checks;
  std::optional<AsFound> as_found;
  std::optional<ValidationRun> validation;
  std::optional<std::int64_t> acceptance_id;  ///< its row in acceptances, once stored
};

/// A unit as `calstand accept --json` prints it (and as the acceptances table stores it):
/// {"device", "serial", "model", "calibration", "run", "verdict", "spec", "k",
/// "decision_rule", "checks": [...], "as_found": {...} or null, "validation": {...} or null}.
nlohmann::json to_json(const UnitAcceptance& unit, const AcceptanceSpec& spec);

}  // namespace calstand::analysis
