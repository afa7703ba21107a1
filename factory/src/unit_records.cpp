#include "factory/unit_records.hpp"

#include <algorithm>
#include <set>

namespace calstand::analysis {

bool may_be_in_force(const std::optional<store::AcceptanceRow>& acceptance) {
  return !acceptance || acceptance->verdict == "pass";
}

std::vector<UnitRecord> unit_records(store::Database& db, const std::string& serial) {
  store::DatabaseRecords records(db);
  return unit_records(records, serial);
}

std::vector<UnitRecord> unit_records(store::RecordSource& records, const std::string& serial) {
  std::vector<store::CalibrationRow> rows;
  if (serial.empty()) {
    rows = records.calibrations_since("");
    // Newest first, as for one unit: created_utc, then id for records made in one second.
    std::reverse(rows.begin(), rows.end());
  } else {
    rows = records.calibrations_of_serial(serial);
  }
  std::vector<UnitRecord> out;
  std::set<std::string> has_one_in_force;
  for (store::CalibrationRow& row : rows) {
    UnitRecord r;
    r.acceptance = records.latest_acceptance(row.id);
    r.in_force = !row.serial.empty() && may_be_in_force(r.acceptance) &&
                 has_one_in_force.insert(row.serial).second;
    r.calibration = std::move(row);
    out.push_back(std::move(r));
  }
  return out;
}

nlohmann::json to_json(const UnitRecord& r) {
  const store::CalibrationRow& c = r.calibration;
  nlohmann::json out = {
      {"id", c.id},
      {"run", c.run},
      {"imu", c.imu},
      {"serial", c.serial},
      {"model", c.model},
      {"created_utc", c.created_utc},
      {"verdict", r.acceptance ? nlohmann::json(r.acceptance->verdict) : nlohmann::json()},
      {"spec", r.acceptance ? nlohmann::json(r.acceptance->spec_name) : nlohmann::json()},
      {"in_force", r.in_force}};
  if (!c.station.empty()) out["station"] = c.station;
  return out;
}

nlohmann::json unit_records_json(const std::string& serial,
                                 const std::vector<UnitRecord>& records) {
  nlohmann::json calibrations = nlohmann::json::array();
  for (const UnitRecord& r : records) calibrations.push_back(to_json(r));
  return {{"serial", serial}, {"calibrations", std::move(calibrations)}};
}

}  // namespace calstand::analysis
