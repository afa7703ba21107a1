#include "factory/acceptance.hpp"

#include <fmt/format.h>

#include "factory/acceptance_names.hpp"

namespace calstand::analysis {
namespace {

AcceptanceCheck make_check(const AcceptanceLimit& limit, CheckSource source) {
  AcceptanceCheck c;
  c.source = source;
  c.spec_limit = limit.where;
  c.limit = limit.value;
  c.unit = limit.unit;
  return c;
}

std::string prefixed(CheckSource source, const std::string& name) {
  return source == CheckSource::kValidation ? "validation " + name : name;
}

// A limit whose names the record does not hold: a check that fails, so that a specification
// naming something the calibration did not measure can never pass by silence.
AcceptanceCheck missing(const AcceptanceLimit& limit, CheckSource source, const std::string& name,
                        const std::string& kind, std::string reason) {
  AcceptanceCheck c = make_check(limit, source);
  c.check = prefixed(source, name);
  c.kind = kind;
  c.verdict = Verdict::kFail;
  c.reason = std::move(reason);
  return c;
}

void judge_value(AcceptanceCheck& c, double value, double sigma, double k) {
  c.value = value;
  c.sigma = sigma;
  const Judgement j = judge(value, sigma, c.limit, k);
  c.verdict = j.verdict;
  c.reason = j.reason;
}

std::string not_in(CheckSource source) {
  return source == CheckSource::kValidation ? "not in the validation fit" : "not in the record";
}

void judge_named(const AcceptanceLimit& limit, const std::vector<RecordValue>& values,
                 const std::string& kind, double k, CheckSource source,
                 std::vector<AcceptanceCheck>& out) {
  bool any = false;
  for (const RecordValue& v : values) {
    if (!glob_match(limit.pattern, v.name)) continue;
    any = true;
    const bool value_limited = limit.value.max_abs || limit.value.min || limit.value.max;
    if (!v.present) {
      if (value_limited) out.push_back(missing(limit, source, v.name, kind, v.note));
      if (limit.max_sigma) {
        AcceptanceCheck c = missing(limit, source, v.name + " sigma", "sigma", v.note);
        c.limit = Bounds{std::nullopt, std::nullopt, *limit.max_sigma};
        out.push_back(std::move(c));
      }
      continue;
    }
    if (v.unit != limit.unit) {
      // The specification's units were checked against the catalogue; a record in another
      // unit is not judged by a number it cannot be compared with.
      out.push_back(missing(
          limit, source, v.name, kind,
          fmt::format("the record gives it in {}, the limit is in {}", v.unit, limit.unit)));
      continue;
    }
    if (value_limited) {
      AcceptanceCheck c = make_check(limit, source);
      c.check = prefixed(source, v.name);
      c.kind = kind;
      judge_value(c, v.value, v.sigma.value_or(0.0), k);
      if (!v.note.empty()) c.reason += " (" + v.note + ")";
      out.push_back(std::move(c));
    }
    if (limit.max_sigma) {
      // The sigma's own uncertainty is not in the record: judged without a guard band.
      AcceptanceCheck c = make_check(limit, source);
      c.check = prefixed(source, v.name + " sigma");
      c.kind = "sigma";
      c.limit = Bounds{std::nullopt, std::nullopt, *limit.max_sigma};
      if (v.sigma) {
        judge_value(c, *v.sigma, 0.0, k);
      } else {
        c.verdict = Verdict::kFail;
        c.reason = "the record gives no sigma";
      }
      out.push_back(std::move(c));
    }
  }
  if (!any) out.push_back(missing(limit, source, limit.pattern, kind, not_in(source)));
}

void judge_temperature(const AcceptanceLimit& limit, const nlohmann::json& record, double k,
                       CheckSource source, std::vector<AcceptanceCheck>& out) {
  // The record's range covers [min, max] when its own min is at or below min and its max at or
  // above max: two one-sided checks on numbers the record states exactly (sigma 0).
  const nlohmann::json range = record.value("valid_temperature_c", nlohmann::json::object());
  const struct {
    const char* end;
    Bounds bounds;
  } ends[] = {{"min", Bounds{std::nullopt, std::nullopt, limit.temperature_min_c}},
              {"max", Bounds{std::nullopt, limit.temperature_max_c, std::nullopt}}};
  for (const auto& e : ends) {
    const std::string name = std::string("valid_temperature_c.") + e.end;
    AcceptanceCheck c = make_check(limit, source);
    c.check = prefixed(source, name);
    c.kind = "temperature";
    c.limit = e.bounds;
    if (!range.contains(e.end) || !range[e.end].is_number()) {
      c.verdict = Verdict::kFail;
      c.reason = "not in the record (recorded without temperature)";
    } else {
      judge_value(c, range[e.end].get<double>(), 0.0, k);
    }
    out.push_back(std::move(c));
  }
}

nlohmann::json optional_number(const std::optional<double>& v) {
  return v ? nlohmann::json(*v) : nlohmann::json();
}

}  // namespace

std::vector<AcceptanceCheck> judge_limits(const nlohmann::json& record,
                                          const std::vector<AcceptanceLimit>& limits, double k,
                                          CheckSource source) {
  std::vector<AcceptanceCheck> out;
  const std::vector<RecordValue> parameters = record_parameters(record);
  const std::vector<RecordValue> noise = record_noise(record);
  const std::vector<RecordValue> fit = record_fit(record);
  for (const AcceptanceLimit& limit : limits) {
    switch (limit.kind) {
      case LimitKind::kParameter:
        judge_named(limit, parameters, "parameter", k, source, out);
        break;
      case LimitKind::kNoise:
        judge_named(limit, noise, "noise", k, source, out);
        break;
      case LimitKind::kFit:
        judge_named(limit, fit, "fit", k, source, out);
        break;
      case LimitKind::kTemperatureRange:
        judge_temperature(limit, record, k, source, out);
        break;
    }
  }
  return out;
}

std::vector<AcceptanceCheck> judge_record(const nlohmann::json& record,
                                          const AcceptanceSpec& spec) {
  return judge_limits(record, spec.limits, spec.k, CheckSource::kRecord);
}

nlohmann::json to_json(const AcceptanceCheck& c) {
  return {{"check", c.check},
          {"kind", c.kind},
          {"source", c.source == CheckSource::kValidation ? "validation" : "record"},
          {"spec_limit", c.spec_limit},
          {"value", optional_number(c.value)},
          {"sigma", optional_number(c.sigma)},
          {"limit", limit_json(c.limit)},
          {"limit_kind", limit_kind(c.limit)},
          {"limit_text", describe(c.limit, c.unit)},
          {"unit", c.unit},
          {"verdict", std::string(to_string(c.verdict))},
          {"reason", c.reason}};
}

Verdict unit_verdict(const std::vector<AcceptanceCheck>& checks) {
  std::vector<Verdict> verdicts;
  verdicts.reserve(checks.size());
  for (const auto& c : checks) verdicts.push_back(c.verdict);
  return combine(verdicts);
}

nlohmann::json to_json(const UnitAcceptance& u, const AcceptanceSpec& spec) {
  nlohmann::json checks = nlohmann::json::array();
  for (const auto& c : u.checks) checks.push_back(to_json(c));
  nlohmann::json validation = nullptr;
  if (u.validation) {
    validation = {{"run", u.validation->run},
                  {"corrected_run", u.validation->corrected_run},
                  {"model", u.validation->model}};
  }
  return {{"device", u.device},
          {"serial", u.serial},
          {"model", u.model},
          {"calibration", u.calibration},
          {"run", u.run},
          {"verdict", std::string(to_string(u.verdict))},
          {"spec", spec_json(spec)},
          {"k", spec.k},
          {"decision_rule", decision_rule_text(spec.k)},
          {"checks", checks},
          {"as_found", u.as_found ? to_json(*u.as_found) : nlohmann::json()},
          {"validation", validation}};
}

}  // namespace calstand::analysis
