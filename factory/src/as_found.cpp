#include "factory/as_found.hpp"

#include <cmath>
#include <limits>
#include <map>

#include "factory/unit_records.hpp"
#include "store/acceptances.hpp"

namespace calstand::analysis {
namespace {

struct Fitted {
  std::string unit;
  double value = 0.0;
  double sigma = 0.0;
};

// The fitted parameters of a record by name, and their order in it.
std::map<std::string, Fitted> fitted(const nlohmann::json& record,
                                     std::vector<std::string>* order) {
  std::map<std::string, Fitted> out;
  for (const auto& p : record.value("parameters", nlohmann::json::array())) {
    const std::string name = p.value("name", "");
    out[name] = {p.value("unit", ""), p.value("value", 0.0), p.value("sigma", 0.0)};
    if (order) order->push_back(name);
  }
  return out;
}

nlohmann::json number_or_null(double v) { return std::isfinite(v) ? nlohmann::json(v) : nullptr; }

}  // namespace

std::optional<store::CalibrationRow> record_in_force_before(
    store::Database& db, const store::CalibrationRow& calibration) {
  if (calibration.serial.empty()) return std::nullopt;
  const std::vector<store::CalibrationRow> rows =
      store::calibrations_of_serial(db, calibration.serial);  // newest first
  bool older = false;
  for (const auto& row : rows) {
    if (row.id == calibration.id) {
      older = true;
      continue;
    }
    // A second record of the same run is the same measurement fitted again, not an earlier
    // state of the unit.
    if (!older || row.run == calibration.run) continue;
    if (!may_be_in_force(store::latest_acceptance(db, row.id))) continue;
    return row;
  }
  return std::nullopt;
}

AsFound compare_records(const store::CalibrationRow& found, const store::CalibrationRow& left) {
  AsFound out;
  out.calibration = found.id;
  out.run = found.run;
  out.created_utc = found.created_utc;
  std::vector<std::string> found_order, left_order;
  const auto before = fitted(found.record, &found_order);
  const auto after = fitted(left.record, &left_order);
  for (const auto& name : left_order) {
    const auto it = before.find(name);
    if (it == before.end()) {
      out.only_new.push_back(name);
      continue;
    }
    const Fitted& f = it->second;
    const Fitted& l = after.at(name);
    ParameterDrift d;
    d.parameter = name;
    d.unit = l.unit;
    d.old_value = f.value;
    d.new_value = l.value;
    d.difference = l.value - f.value;
    d.combined_sigma = std::hypot(f.sigma, l.sigma);
    d.difference_sigmas = d.combined_sigma > 0.0 ? d.difference / d.combined_sigma
                                                 : std::numeric_limits<double>::quiet_NaN();
    out.parameters.push_back(std::move(d));
  }
  for (const auto& name : found_order) {
    if (!after.count(name)) out.only_old.push_back(name);
  }
  return out;
}

std::optional<AsFound> as_found(store::Database& db, const store::CalibrationRow& calibration) {
  const auto found = record_in_force_before(db, calibration);
  if (!found) return std::nullopt;
  AsFound out = compare_records(*found, calibration);
  if (const auto judged = store::latest_acceptance(db, found->id)) out.verdict = judged->verdict;
  return out;
}

nlohmann::json to_json(const AsFound& d) {
  nlohmann::json parameters = nlohmann::json::array();
  for (const auto& p : d.parameters) {
    parameters.push_back({{"parameter", p.parameter},
                          {"unit", p.unit},
                          {"old_value", p.old_value},
                          {"new_value", p.new_value},
                          {"difference", p.difference},
                          {"combined_sigma", p.combined_sigma},
                          {"difference_sigmas", number_or_null(p.difference_sigmas)}});
  }
  return {{"calibration", d.calibration},
          {"run", d.run},
          {"created_utc", d.created_utc},
          {"verdict", d.verdict.empty() ? nlohmann::json() : nlohmann::json(d.verdict)},
          {"parameters", parameters},
          {"only_old", d.only_old},
          {"only_new", d.only_new}};
}

}  // namespace calstand::analysis
