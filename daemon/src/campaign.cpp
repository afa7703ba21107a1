#include "daemon/campaign.hpp"

#include <utility>

#include "daemon/station_run.hpp"

namespace calstand::daemon {

std::int64_t create_run_record(store::RunStore& runs, const core::StationConfig& station,
                               const procedures::Procedure& procedure,
                               const procedures::Plan& plan) {
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
