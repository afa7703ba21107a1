#include "daemon/campaign.hpp"

#include <algorithm>
#include <utility>

#include "core/error.hpp"
#include "daemon/station_run.hpp"

namespace calstand::daemon {

std::vector<store::RunUnit> units_for_run(const core::StationConfig& station,
                                          const UnitSerials& submitted) {
  for (const auto& [name, serial] : submitted) {
    const bool known = std::any_of(station.imus.begin(), station.imus.end(),
                                   [&](const core::ImuConfig& imu) { return imu.name == name; });
    if (!known) {
      std::string names;
      for (const auto& imu : station.imus) names += (names.empty() ? "" : ", ") + imu.name;
      throw core::InputError(
          "units." + name,
          "station " + station.name + " has no IMU of that name (it has " + names + ")");
    }
    if (serial.empty()) throw core::InputError("units." + name, "the serial is empty");
  }
  std::vector<store::RunUnit> units;
  for (const auto& imu : station.imus) {
    store::RunUnit u;
    u.imu = imu.name;
    u.model = imu.model;
    if (auto it = submitted.find(imu.name); it != submitted.end()) {
      u.serial = it->second;
      u.source = "submitted";
    } else {
      u.serial = imu.serial;
      u.source = "station";
    }
    if (station.require_serial && u.serial.empty()) {
      throw core::InputError(
          "units." + imu.name,
          "station " + station.name +
              " requires a serial for every unit and this one has none: give it with the run "
              "(--unit " +
              imu.name + "=SN, or \"units\" in POST /runs)");
    }
    units.push_back(std::move(u));
  }
  return units;
}

std::int64_t create_run_record(store::RunStore& runs, const core::StationConfig& station,
                               const procedures::Procedure& procedure, const procedures::Plan& plan,
                               const UnitSerials& submitted) {
  const std::vector<store::RunUnit> units = units_for_run(station, submitted);
  std::vector<store::DeviceRecord> devices{{"table", "table", station.table.backend},
                                           {"chamber", "chamber", station.chamber.backend}};
  for (const auto& imu : station.imus) devices.push_back({"imu", imu.name, imu.backend});
  store::NewRun run;
  run.station_id = runs.upsert_station(station.name, station.to_json(), devices);
  run.procedure_name = procedure.name;
  run.procedure_text = procedure.source_text;
  run.parameters = plan.parameters;
  run.station_snapshot = station.to_json();
  const std::int64_t run_id = runs.create_run(run);
  std::vector<store::NewStep> steps;
  for (const auto& s : plan.steps) {
    steps.push_back(
        {std::string(procedures::to_string(s.kind)), s.label, s.to_json(), s.origin_path});
  }
  runs.add_steps(run_id, steps);
  store::record_run_units(runs.database(), run_id, units);
  return run_id;
}

CampaignResult run_campaign(const core::StationConfig& station_config, const procedures::Plan& plan,
                            const std::string& db_path, std::int64_t run_id,
                            const CampaignStart& start,
                            std::function<void(RunEngine&, const Progress&)> on_tick) {
  StationRun wired(station_config, db_path, run_id, start.start_time_s);
  return wired.run(plan, start, wired.store_journal(), std::move(on_tick));
}

}  // namespace calstand::daemon
