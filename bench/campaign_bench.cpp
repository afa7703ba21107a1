// The whole thermal-calibration campaign (library defaults: 7 plateaus, 24 orientations and a
// rate ladder at each, about 12 h of lab time) on the simulated station, through the engine
// and the capture writer into a WAL database on disk. Target (issue 3): 1000x real time.
//
//   build/bench/calstand_bench --benchmark_filter=Campaign
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <filesystem>
#include <string>

#include "daemon/campaign.hpp"
#include "procedures/plan.hpp"
#include "procedures/procedure.hpp"
#include "sim/sim_world.hpp"
#include "store/database.hpp"
#include "store/run_store.hpp"

namespace calstand::daemon {
namespace {

void BM_ThermalCalibrationCampaign(benchmark::State& state) {
  const core::StationConfig station = sim::default_station();
  const auto procedure = procedures::load_procedure("thermal-calibration");
  const auto plan = procedures::make_plan(procedure, station);
  const auto dir = std::filesystem::temp_directory_path();
  const std::string db_path =
      (dir / ("calstand_campaign_bench_" + std::to_string(getpid()) + ".db")).string();
  double station_s = 0.0;
  double bytes = 0.0;
  for (auto _ : state) {
    state.PauseTiming();
    for (const char* suffix : {"", "-wal", "-shm"}) std::filesystem::remove(db_path + suffix);
    std::int64_t run_id = 0;
    {
      store::Database db(db_path);
      store::RunStore runs(db);
      run_id = create_run_record(runs, station, procedure, plan);
    }
    state.ResumeTiming();
    const auto result = run_campaign(station, plan, db_path, run_id);
    if (result.state != RunState::kCompleted) state.SkipWithError(result.exit_reason.c_str());
    station_s += result.station_time_s;
    bytes = static_cast<double>(std::filesystem::file_size(db_path));
  }
  for (const char* suffix : {"", "-wal", "-shm"}) std::filesystem::remove(db_path + suffix);
  // Station seconds per wall second: the real-time factor of the whole campaign.
  state.counters["realtime_factor"] = benchmark::Counter(station_s, benchmark::Counter::kIsRate);
  state.counters["station_hours"] = station_s / 3600.0 / static_cast<double>(state.iterations());
  state.counters["db_MB"] = bytes / 1e6;
}
BENCHMARK(BM_ThermalCalibrationCampaign)->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();

}  // namespace
}  // namespace calstand::daemon
