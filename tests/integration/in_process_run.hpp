#pragma once
// A library procedure run in process on a simulated station, as `calstand run` runs it (plan,
// engine, SQLite), for the tests that analyse what it recorded.

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "core/station_config.hpp"
#include "daemon/campaign.hpp"
#include "procedures/plan.hpp"
#include "procedures/procedure.hpp"
#include "sim/sim_world.hpp"
#include "store/database.hpp"
#include "store/run_store.hpp"

namespace calstand::testing {

/// A fresh database file of this process (ctest runs tests two at a time, each in a process).
inline std::string fresh_db(const std::string& name) {
  const std::string path =
      ::testing::TempDir() + "calstand_library_" + std::to_string(getpid()) + "_" + name + ".db";
  for (const char* suffix : {"", "-wal", "-shm"}) std::filesystem::remove(path + suffix);
  return path;
}

inline void remove_db(const std::string& path) {
  for (const char* suffix : {"", "-wal", "-shm"}) std::filesystem::remove(path + suffix);
}

/// Runs library procedure `name` with `overrides` on `station` into the database at `db_path`,
/// as `calstand run` does; returns the run id. A plan that fails or a run that does not complete
/// is a test failure.
inline std::int64_t run_procedure(const std::string& name,
                                  const std::vector<std::string>& overrides,
                                  const std::string& db_path,
                                  const core::StationConfig& station = sim::default_station()) {
  const auto procedure = procedures::load_procedure(name);
  const auto plan =
      procedures::make_plan(procedure, station, procedures::parse_overrides(overrides));
  EXPECT_TRUE(plan.ok()) << name;
  std::int64_t run_id = 0;
  {
    store::Database db(db_path);
    store::RunStore runs(db);
    run_id = daemon::create_run_record(runs, station, procedure, plan);
  }
  const auto result = daemon::run_campaign(station, plan, db_path, run_id);
  EXPECT_EQ(result.state, daemon::RunState::kCompleted) << name << ": " << result.exit_reason;
  return run_id;
}

}  // namespace calstand::testing
