#include "daemon/campaign.hpp"

#include "daemon/store_journal.hpp"
#include "drivers/station.hpp"
#include "store/capture_writer.hpp"
#include "store/database.hpp"

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
    steps.push_back({std::string(procedures::to_string(s.kind)), s.label, s.to_json(), s.origin_path});
  }
  runs.add_steps(run_id, steps);
  return run_id;
}

CampaignResult run_campaign(const core::StationConfig& station_config,
                            const procedures::Plan& plan, const std::string& db_path,
                            std::int64_t run_id, const CampaignStart& start,
                            std::function<void(RunEngine&, const Progress&)> on_tick) {
  store::Database db(db_path);
  store::RunStore runs(db);
  store::CaptureWriter writer(db_path);
  auto station = drivers::make_station(station_config, start.start_time_s);
  StoreJournal journal(runs, writer, run_id, 0.1, station->clock().is_virtual());
  EngineOptions options = EngineOptions::from_policy(station_config.policy);
  RunEngine* engine_ptr = nullptr;
  options.on_progress = [&](const Progress& p) {
    if (on_tick && engine_ptr) on_tick(*engine_ptr, p);
  };
  RunEngine engine(*station, journal, plan, options);
  engine_ptr = &engine;
  CampaignResult result;
  result.state = engine.run(start.first_step, start.first_attempt, start.skipped_steps);
  result.exit_reason = engine.exit_reason();
  result.station_time_s = station->clock().now_s();
  return result;
}

}  // namespace calstand::daemon
