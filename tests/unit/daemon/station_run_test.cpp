#include "daemon/station_run.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <string>

#include "daemon/campaign.hpp"
#include "procedures/plan.hpp"
#include "procedures/procedure.hpp"
#include "sim/sim_world.hpp"
#include "store/database.hpp"
#include "store/run_store.hpp"
#include "store/sample_reader.hpp"

namespace calstand::daemon {
namespace {

/// A database file of this process, removed (with its WAL files) before and after.
struct StationRunDatabase {
  std::string path = (std::filesystem::temp_directory_path() /
                      ("calstand-station-run-" + std::to_string(::getpid()) + ".db"))
                         .string();
  StationRunDatabase() { remove(); }
  ~StationRunDatabase() { remove(); }
  void remove() const {
    std::error_code ignored;
    for (const char* suffix : {"", "-wal", "-shm", ".lock"})
      std::filesystem::remove(path + suffix, ignored);
  }
};

TEST(StationRun, RecordsTheCaptureWritersCountersAndQueueHighWaterAsAnEvent) {
  StationRunDatabase db_file;
  const core::StationConfig station = sim::default_station();
  const auto procedure = procedures::load_procedure("two-position");
  const auto plan =
      procedures::make_plan(procedure, station, procedures::parse_overrides({"capture_s=2"}));
  std::int64_t run = 0;
  {
    store::Database db(db_file.path);
    store::RunStore runs(db);
    run = create_run_record(runs, station, procedure, plan);
  }
  ASSERT_EQ(run_campaign(station, plan, db_file.path, run).state, RunState::kCompleted);

  store::Database db(db_file.path);
  const auto record = store::RunStore(db).load_run(run);
  std::uint64_t stored = 0;
  for (const auto& step : record.steps) {
    for (const auto& device : store::sample_devices(db, run))
      stored += store::read_samples(db, run, step.index, device).size();
  }
  ASSERT_GT(stored, 0u);
  int summaries = 0;
  for (const auto& e : record.events) {
    if (e.source != "capture_writer") continue;
    ++summaries;
    EXPECT_EQ(e.kind, store::EventKind::kInfo);
    EXPECT_NE(e.message.find("queue high-water"), std::string::npos) << e.message;
    EXPECT_EQ(e.detail.at("written").get<std::uint64_t>(), stored);
    EXPECT_EQ(e.detail.at("dropped_queue_full").get<std::uint64_t>(), 0u);
    const auto high_water = e.detail.at("queue_high_water").get<std::uint64_t>();
    EXPECT_GT(high_water, 0u);
    EXPECT_LE(high_water, e.detail.at("queue_capacity").get<std::uint64_t>());
  }
  EXPECT_EQ(summaries, 1);
}

}  // namespace
}  // namespace calstand::daemon
