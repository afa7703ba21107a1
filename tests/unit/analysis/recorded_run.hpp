#pragma once
// Runs recorded for the analysis tests: a library procedure on the simulated station whose IMU
// has known errors and white noise only (tests/integration/known_imu_station.hpp), run in
// process by the engine into a fresh database file, as `calstand run` records it.

#include <unistd.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "../../integration/known_imu_station.hpp"
#include "core/station_config.hpp"
#include "daemon/campaign.hpp"
#include "procedures/plan.hpp"
#include "procedures/procedure.hpp"
#include "store/database.hpp"
#include "store/run_store.hpp"

namespace calstand::testing {

/// A database file of this process and test, removed (with its WAL files) on destruction.
class TempDatabase {
 public:
  explicit TempDatabase(const std::string& name)
      : path_((std::filesystem::temp_directory_path() /
               ("calstand-analysis-" + std::to_string(::getpid()) + "-" + name + ".db"))
                  .string()) {
    remove();
  }
  ~TempDatabase() { remove(); }
  TempDatabase(const TempDatabase&) = delete;
  TempDatabase& operator=(const TempDatabase&) = delete;
  const std::string& path() const { return path_; }

 private:
  void remove() {
    std::error_code ignored;
    for (const char* suffix : {"", "-wal", "-shm"})
      std::filesystem::remove(path_ + suffix, ignored);
  }
  std::string path_;
};

inline core::StationConfig known_station(int seed) {
  return core::StationConfig::from_json(nlohmann::json::parse(known_imu_station("known", seed)),
                                        "known-imu-station");
}

/// Records library procedure `name` with `overrides` (e.g. "capture_s=10") on the known-IMU
/// station seeded with `seed`; returns the run id. `run` = false only records the run and its
/// steps (no samples).
inline std::int64_t record_run(const std::string& db_path, const std::string& name,
                               const std::vector<std::string>& overrides, int seed,
                               bool run = true) {
  const core::StationConfig station = known_station(seed);
  const auto procedure = procedures::load_procedure(name);
  const auto plan =
      procedures::make_plan(procedure, station, procedures::parse_overrides(overrides));
  std::int64_t run_id = 0;
  {
    store::Database db(db_path);
    store::RunStore runs(db);
    run_id = daemon::create_run_record(runs, station, procedure, plan);
  }
  if (run) daemon::run_campaign(station, plan, db_path, run_id);
  return run_id;
}

}  // namespace calstand::testing
