#include "daemon/station_run.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <string>

#include "core/error.hpp"
#include "daemon/campaign.hpp"
#include "procedures/plan.hpp"
#include "procedures/procedure.hpp"
#include "sim/sim_world.hpp"
#include "store/database.hpp"
#include "store/run_store.hpp"
#include "store/sample_reader.hpp"
#include "store/units.hpp"

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

namespace calstand::daemon {
namespace {

/// The default station with three simulated units on a fixture, each with its serial plate.
core::StationConfig fixture_station(bool require_serial) {
  core::StationConfig station = sim::default_station();
  const core::ImuConfig base = station.imus.at(0);
  station.imus.clear();
  for (int i = 0; i < 3; ++i) {
    core::ImuConfig imu = base;
    imu.name = "imu" + std::to_string(i);
    imu.serial = i == 1 ? "" : "SN-" + std::to_string(i);  // imu1's plate cannot be read
    station.imus.push_back(imu);
  }
  station.require_serial = require_serial;
  return station;
}

TEST(UnitsForRun, TheSerialGivenWinsOverTheStationFileAndEveryRuleNamesTheUnit) {
  const core::StationConfig station = fixture_station(false);
  const auto units = units_for_run(station, {{"imu1", "SN-X"}});
  ASSERT_EQ(units.size(), 3u);
  EXPECT_EQ(units[0].serial, "SN-0");
  EXPECT_EQ(units[0].source, "station");
  EXPECT_EQ(units[1].serial, "SN-X");
  EXPECT_EQ(units[1].source, "submitted");

  try {
    units_for_run(station, {{"imu7", "SN-7"}});
    FAIL() << "an unknown slot was accepted";
  } catch (const core::InputError& e) {
    EXPECT_EQ(e.where(), "units.imu7");
    EXPECT_NE(std::string(e.what()).find("imu0, imu1, imu2"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(units_for_run(station, {}));  // a lab station: a unit may have no serial
  try {
    units_for_run(fixture_station(true), {});
    FAIL() << "a production station accepted a unit without a serial";
  } catch (const core::InputError& e) {
    EXPECT_EQ(e.where(), "units.imu1");
    EXPECT_NE(std::string(e.what()).find("--unit imu1=SN"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(units_for_run(fixture_station(true), {{"imu1", "SN-1"}}));
}

TEST(UnitsForRun, AnotherUnitInASlotFailsTheRunBeforeAnythingIsRecordedAndSaysWhich) {
  StationRunDatabase db_file;
  const core::StationConfig station = fixture_station(false);
  const auto procedure = procedures::load_procedure("two-position");
  const auto plan =
      procedures::make_plan(procedure, station, procedures::parse_overrides({"capture_s=1"}));
  std::int64_t good = 0;
  std::int64_t wrong = 0;
  {
    store::Database db(db_file.path);
    store::RunStore runs(db);
    good = create_run_record(runs, station, procedure, plan, {{"imu1", "SN-1"}});
    wrong = create_run_record(runs, station, procedure, plan, {{"imu2", "SN-9"}});
  }
  ASSERT_EQ(run_campaign(station, plan, db_file.path, good).state, RunState::kCompleted);
  const CampaignResult refused = run_campaign(station, plan, db_file.path, wrong);
  EXPECT_EQ(refused.state, RunState::kFailed);
  EXPECT_NE(refused.exit_reason.find("imu2 reports serial SN-2"), std::string::npos)
      << refused.exit_reason;
  EXPECT_NE(refused.exit_reason.find("SN-9"), std::string::npos) << refused.exit_reason;

  store::Database db(db_file.path);
  const auto units = store::units_of_run(db, good);
  ASSERT_EQ(units.size(), 3u);
  EXPECT_EQ(units[0].source, "device");  // read from the unit, as reported
  EXPECT_EQ(units[1].serial, "SN-1");
  EXPECT_EQ(units[1].source, "submitted");  // a plate nobody can read: as given
  EXPECT_EQ(units[2].serial, "SN-2");
  for (const auto& step : store::RunStore(db).load_run(wrong).steps) {
    EXPECT_EQ(store::read_samples(db, wrong, step.index, "imu2").size(), 0u) << step.label;
  }
}

}  // namespace
}  // namespace calstand::daemon
