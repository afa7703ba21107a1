// `calstand fit` on a default thermal calibration recorded at the LN200's 400 Hz (issue 28
// target: the fit under 2 s). The run is recorded once per process through the engine into a
// database on disk (library defaults: 7 plateaus, 24 orientations and a rate ladder at each;
// about a minute), then timed apart:
//   BM_FitThermalCalibration400Hz   the solver's part, solver::fit_run on the loaded run: the
//                                   noise superset's step summaries, the noise model, the fit;
//   BM_LoadThermalCalibration400Hz  reading the run's samples and table state from SQLite.
// `calstand fit --db X --run 1` does both, plus opening the database and printing.
//
//   build/bench/calstand_bench --benchmark_filter=ThermalCalibration400Hz
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <filesystem>
#include <stdexcept>
#include <string>

#include "analysis/run_model.hpp"
#include "daemon/campaign.hpp"
#include "procedures/plan.hpp"
#include "procedures/procedure.hpp"
#include "sim/sim_world.hpp"
#include "solver/noise_estimate.hpp"
#include "store/database.hpp"
#include "store/run_store.hpp"

namespace calstand {
namespace {

struct RecordedRun {
  std::string db_path;
  std::int64_t run_id = 0;
  ~RecordedRun() {
    // The database, its WAL files and the lock file store::Database takes beside it.
    for (const char* suffix : {"", "-wal", "-shm", ".lock"}) {
      std::filesystem::remove(db_path + suffix);
    }
  }
};

/// The default thermal calibration on the built-in station (its LN200 outputs at 400 Hz),
/// recorded once per process.
const RecordedRun& thermal_calibration_run() {
  static const RecordedRun run = [] {
    RecordedRun r;
    r.db_path = (std::filesystem::temp_directory_path() /
                 ("calstand_fit_thermal_bench_" + std::to_string(getpid()) + ".db"))
                    .string();
    const core::StationConfig station = sim::default_station();
    const auto procedure = procedures::load_procedure("thermal-calibration");
    const auto plan = procedures::make_plan(procedure, station);
    {
      store::Database db(r.db_path);
      store::RunStore runs(db);
      r.run_id = daemon::create_run_record(runs, station, procedure, plan);
    }
    const auto result = daemon::run_campaign(station, plan, r.db_path, r.run_id);
    if (result.state != daemon::RunState::kCompleted) {
      throw std::runtime_error("thermal calibration run: " + result.exit_reason);
    }
    return r;
  }();
  return run;
}

const solver::RunData& thermal_calibration_data() {
  static const solver::RunData data = [] {
    store::Database db(thermal_calibration_run().db_path);
    return analysis::load_fit_data(db, thermal_calibration_run().run_id, "");
  }();
  return data;
}

double sample_count(const solver::RunData& d) {
  double n = 0.0;
  for (const auto& s : d.steps) n += static_cast<double>(s.samples.size());
  return n;
}

// The model and options of `calstand fit --db X --run 1`.
void BM_FitThermalCalibration400Hz(benchmark::State& state) {
  const solver::RunData& data = thermal_calibration_data();
  const solver::Model model = solver::Model::parse(analysis::kDefaultModel);
  for (auto _ : state) {
    std::vector<solver::StepSummary> steps;
    const solver::FitResult fit = solver::fit_run(data, model, {}, {}, &steps);
    benchmark::DoNotOptimize(fit.chi2);
  }
  state.counters["samples"] = sample_count(data);
  state.counters["steps"] = static_cast<double>(data.steps.size());
}
BENCHMARK(BM_FitThermalCalibration400Hz)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_LoadThermalCalibration400Hz(benchmark::State& state) {
  const RecordedRun& run = thermal_calibration_run();
  store::Database db(run.db_path);
  double samples = 0.0;
  for (auto _ : state) {
    const solver::RunData data = analysis::load_fit_data(db, run.run_id, "");
    samples = sample_count(data);
    benchmark::DoNotOptimize(samples);
  }
  state.counters["samples"] = samples;
}
BENCHMARK(BM_LoadThermalCalibration400Hz)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace calstand
