// The units of a run and a unit's calibrations, found by serial (migration 5).
#include "store/units.hpp"

#include <gtest/gtest.h>

#include "core/error.hpp"
#include "store/acceptances.hpp"
#include "store/calibrations.hpp"
#include "store/run_store.hpp"

namespace calstand::store {
namespace {

class UnitsTest : public ::testing::Test {
 protected:
  std::int64_t new_run() {
    NewRun r;
    r.procedure_name = "six-position";
    r.procedure_text = "{}";
    r.parameters = nlohmann::json::object();
    r.station_snapshot = {{"name", "fixture"}};
    const std::int64_t id = runs_.create_run(r);
    runs_.add_steps(id, {{"capture", "z up", {{"duration_s", 1.0}}, "steps[0]"}});
    return id;
  }
  static nlohmann::json record_of(const std::string& serial) {
    return {{"device", {{"name", "imu0"}, {"model", "ln200"}, {"serial", serial}}}};
  }
  Database db_{":memory:"};
  RunStore runs_{db_};
};

TEST_F(UnitsTest, TheDeviceReadingReplacesWhatTheRunWasGivenAndRunsAreFoundBySerial) {
  const std::int64_t first = new_run();
  const std::int64_t second = new_run();
  record_run_units(db_, first,
                   {{"imu1", "ln200", "SN2", "submitted"}, {"imu0", "ln200", "SN1", "station"}});
  record_run_units(db_, first, {{"imu0", "ln200", "SN1", "device"}});
  record_run_units(db_, second, {{"imu0", "", "SN2", "submitted"}});

  const auto units = units_of_run(db_, first);
  ASSERT_EQ(units.size(), 2u);
  EXPECT_EQ(units[0].imu, "imu0");  // slot-name order
  EXPECT_EQ(units[0].source, "device");
  EXPECT_EQ(units[1].serial, "SN2");
  EXPECT_EQ(runs_.load_run(first).units.size(), 2u);
  EXPECT_EQ(runs_of_serial(db_, "SN2"), (std::vector<std::int64_t>{first, second}));
  EXPECT_TRUE(runs_of_serial(db_, "SN9").empty());
  EXPECT_EQ(unit_of_run(db_, second, "imu3").serial, "");  // never recorded: no serial
}

TEST_F(UnitsTest, AUnitsCalibrationsComeNewestFirstWithTheirLatestVerdict) {
  const std::int64_t run = new_run();
  const std::int64_t a = insert_calibration(db_, run, "imu0", "gyro_bias", record_of("SN1"));
  const std::int64_t other = insert_calibration(db_, run, "imu1", "gyro_bias", record_of("SN2"));
  const std::int64_t b = insert_calibration(db_, run, "imu0", "gyro_bias", record_of("SN1"));
  const auto rows = calibrations_of_serial(db_, "SN1");
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0].id, b);
  EXPECT_EQ(rows[1].id, a);
  EXPECT_EQ(rows[0].serial, "SN1");
  EXPECT_EQ(calibrations_since(db_, "").size(), 3u);
  EXPECT_TRUE(calibrations_since(db_, "9999").empty());

  EXPECT_FALSE(latest_acceptance(db_, b).has_value());
  insert_acceptance(db_, b, "spec", std::string(64, 'a'), "fail", {{"k", 2}});
  insert_acceptance(db_, b, "spec", std::string(64, 'a'), "pass", {{"k", 2}});
  const auto judged = latest_acceptance(db_, b);
  ASSERT_TRUE(judged.has_value());
  EXPECT_EQ(judged->verdict, "pass");
  EXPECT_EQ(judged->result["k"], 2);
  EXPECT_THROW(insert_acceptance(db_, other, "spec", "", "maybe", {}), core::InputError);
  EXPECT_THROW(insert_acceptance(db_, 999, "spec", "", "pass", {}), core::InputError);
}

}  // namespace
}  // namespace calstand::store
