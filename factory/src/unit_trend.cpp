#include "factory/unit_trend.hpp"

#include <algorithm>
#include <cmath>
#include <map>

#include "core/error.hpp"
#include "factory/unit_records.hpp"

namespace calstand::analysis {

UnitTrend unit_trend(store::Database& db, const std::string& serial) {
  store::DatabaseRecords records(db);
  return unit_trend(records, serial);
}

UnitTrend unit_trend(store::RecordSource& records, const std::string& serial) {
  std::vector<UnitRecord> rows =
      serial.empty() ? std::vector<UnitRecord>() : unit_records(records, serial);
  if (serial.empty() || rows.empty()) {
    throw core::InputError("--serial " + serial, "no calibration record of that unit");
  }
  std::reverse(rows.begin(), rows.end());  // oldest first: time runs left to right
  UnitTrend trend;
  trend.serial = serial;
  std::map<std::string, std::size_t> index;
  for (std::size_t r = 0; r < rows.size(); ++r) {
    const store::CalibrationRow& c = rows[r].calibration;
    trend.records.push_back({c.id, c.run, c.created_utc,
                             rows[r].acceptance ? rows[r].acceptance->verdict : std::string(),
                             c.station});
    for (const auto& p : c.record.value("parameters", nlohmann::json::array())) {
      const std::string name = p.value("name", "");
      auto [it, added] = index.emplace(name, trend.parameters.size());
      if (added) {
        TrendParameter tp;
        tp.name = name;
        tp.unit = p.value("unit", "");
        tp.values.assign(rows.size(), std::nullopt);
        tp.sigmas.assign(rows.size(), std::nullopt);
        trend.parameters.push_back(std::move(tp));
      }
      TrendParameter& tp = trend.parameters[it->second];
      tp.values[r] = p.value("value", 0.0);
      tp.sigmas[r] = p.value("sigma", 0.0);
    }
  }
  for (TrendParameter& tp : trend.parameters) {
    std::optional<std::size_t> first;
    std::optional<std::size_t> last;
    for (std::size_t r = 0; r < tp.values.size(); ++r) {
      if (!tp.values[r]) continue;
      if (!first) first = r;
      last = r;
    }
    if (!first || *first == *last) continue;
    tp.change = *tp.values[*last] - *tp.values[*first];
    tp.change_sigma = std::hypot(*tp.sigmas[*first], *tp.sigmas[*last]);
    if (tp.change_sigma > 0.0) tp.change_z = tp.change / tp.change_sigma;
  }
  return trend;
}

namespace {

nlohmann::json optional_array(const std::vector<std::optional<double>>& v) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& x : v) out.push_back(x ? nlohmann::json(*x) : nlohmann::json());
  return out;
}

}  // namespace

nlohmann::json to_json(const UnitTrend& trend) {
  nlohmann::json records = nlohmann::json::array();
  for (const TrendRecord& r : trend.records) {
    records.push_back(
        {{"calibration", r.calibration},
         {"run", r.run},
         {"created_utc", r.created_utc},
         {"verdict", r.verdict.empty() ? nlohmann::json() : nlohmann::json(r.verdict)}});
    if (!r.station.empty()) records.back()["station"] = r.station;
  }
  nlohmann::json parameters = nlohmann::json::array();
  for (const TrendParameter& p : trend.parameters) {
    parameters.push_back(
        {{"name", p.name},
         {"unit", p.unit},
         {"values", optional_array(p.values)},
         {"sigmas", optional_array(p.sigmas)},
         {"change", p.change},
         {"change_sigma", p.change_sigma},
         {"change_z", p.change_z ? nlohmann::json(*p.change_z) : nlohmann::json()}});
  }
  return {{"serial", trend.serial}, {"records", records}, {"parameters", parameters}};
}

}  // namespace calstand::analysis
