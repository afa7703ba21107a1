#include "factory/accept_run.hpp"

#include <fmt/format.h>

#include <map>

#include "analysis/run_model.hpp"
#include "core/error.hpp"
#include "factory/acceptance_validation.hpp"
#include "factory/as_found.hpp"
#include "store/acceptances.hpp"
#include "store/calibrations.hpp"
#include "store/run_store.hpp"

namespace calstand::analysis {
namespace {

// The validation part's checks when the specification asks for a validation run and none was
// given: each fails, so that a unit is never accepted without the evidence its specification
// requires.
std::vector<AcceptanceCheck> without_validation_run(const ValidationSpec& validation) {
  std::vector<AcceptanceCheck> out;
  for (const auto& limit : validation.limits) {
    AcceptanceCheck c;
    c.check = "validation " + limit.pattern;
    c.kind = std::string(to_string(limit.kind));
    c.source = CheckSource::kValidation;
    c.spec_limit = limit.where;
    c.limit = limit.value;
    // A limit on the sigma alone shows that bound (it is what the check would have judged).
    if (limit.max_sigma && !c.limit.max_abs && !c.limit.min && !c.limit.max) {
      c.limit.max = *limit.max_sigma;
    }
    c.unit = limit.unit;
    c.verdict = Verdict::kFail;
    c.reason = "no validation run given (--validation-run): the specification asks for one";
    out.push_back(std::move(c));
  }
  return out;
}

}  // namespace

AcceptanceOutcome accept_run(store::Database& db, const AcceptanceSpec& spec,
                             const AcceptRequest& request) {
  try {
    store::RunStore(db).run_status(request.run);  // throws for an unknown run
  } catch (const core::InputError&) {
    throw RunNotFound(fmt::format("run {}", request.run), "no such run");
  }
  // The newest record of each unit: a unit calibrated again keeps its older records in the
  // database, but only the latest is the one to hand over.
  std::map<std::string, store::CalibrationRow> newest;
  for (auto& row : store::calibrations_of_run(db, request.run)) {
    if (!request.device.empty() && row.imu != request.device) continue;
    newest[row.imu] = std::move(row);  // oldest first: the last one wins
  }
  if (newest.empty()) {
    const std::string what = request.device.empty() ? "no calibration record"
                                                    : "no calibration record of " + request.device;
    throw NoCalibrationRecord(
        fmt::format("run {}", request.run),
        fmt::format("{} (calstand calibrate --run {}{} first)", what, request.run,
                    request.device.empty() ? "" : " --device " + request.device));
  }

  AcceptanceOutcome out;
  out.run = request.run;
  out.spec = spec;
  out.validation_run = request.validation_run;
  std::vector<Verdict> verdicts;
  for (const auto& [imu, row] : newest) {
    UnitAcceptance u;
    u.device = imu;
    u.serial = row.serial;
    u.model = row.record.contains("device") ? row.record["device"].value("model", "") : "";
    u.calibration = row.id;
    u.run = row.run;
    u.checks = judge_record(row.record, spec);
    u.as_found = as_found(db, row);
    if (spec.validation) {
      if (request.validation_run) {
        const ValidationFit v =
            fit_validation_run(db, row, *request.validation_run, *spec.validation);
        u.validation = ValidationRun{v.run, v.corrected_run, v.model};
        for (auto& c : judge_limits(v.residual_record, spec.validation->limits, spec.k,
                                    CheckSource::kValidation)) {
          u.checks.push_back(std::move(c));
        }
      } else {
        for (auto& c : without_validation_run(*spec.validation)) u.checks.push_back(std::move(c));
      }
    }
    u.verdict = unit_verdict(u.checks);
    verdicts.push_back(u.verdict);
    out.units.push_back(std::move(u));
  }
  out.verdict = combine(verdicts);
  return out;
}

void store_acceptances(store::Database& db, AcceptanceOutcome& outcome) {
  for (auto& u : outcome.units) {
    u.acceptance_id =
        store::insert_acceptance(db, u.calibration, outcome.spec.name, outcome.spec.sha256,
                                 std::string(to_string(u.verdict)), to_json(u, outcome.spec));
  }
}

nlohmann::json to_json(const AcceptanceOutcome& o) {
  nlohmann::json units = nlohmann::json::array();
  for (const auto& u : o.units) {
    nlohmann::json j = to_json(u, o.spec);
    j["acceptance_id"] = u.acceptance_id ? nlohmann::json(*u.acceptance_id) : nlohmann::json();
    units.push_back(std::move(j));
  }
  return {{"run", o.run},
          {"spec", spec_json(o.spec)},
          {"k", o.spec.k},
          {"decision_rule", decision_rule_text(o.spec.k)},
          {"validation_run", o.validation_run ? nlohmann::json(*o.validation_run) : nullptr},
          {"verdict", std::string(to_string(o.verdict))},
          {"units", units}};
}

}  // namespace calstand::analysis
