// A unit's trend over its records: values in time order, a parameter missing from one record,
// and the change beside the two records' combined uncertainty.
#include "factory/unit_trend.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "core/error.hpp"
#include "store/calibrations.hpp"
#include "store/run_store.hpp"

namespace calstand::analysis {
namespace {

TEST(UnitTrend, ChangesAreInTimeOrderAndWeighedAgainstBothRecordsSigmas) {
  store::Database db(":memory:");
  store::RunStore runs(db);
  store::NewRun r;
  r.procedure_name = "six-position";
  r.procedure_text = "{}";
  r.parameters = nlohmann::json::object();
  r.station_snapshot = {{"name", "lab"}};
  const std::int64_t run = runs.create_run(r);
  runs.add_steps(run, {{"capture", "z up", {{"duration_s", 1.0}}, "steps[0]"}});
  const auto record = [](double bias, double sigma, bool with_scale) {
    nlohmann::json params = {
        {{"name", "gyro_bias.x"}, {"value", bias}, {"sigma", sigma}, {"unit", "deg/s"}}};
    if (with_scale) {
      params.push_back(
          {{"name", "gyro_scale.x"}, {"value", 100.0}, {"sigma", 5.0}, {"unit", "ppm"}});
    }
    return nlohmann::json{{"device", {{"name", "imu0"}, {"model", ""}, {"serial", "SN7"}}},
                          {"parameters", params}};
  };
  store::insert_calibration(db, run, "imu0", "m", record(1.0e-3, 3e-5, true));
  store::insert_calibration(db, run, "imu0", "m", record(1.2e-3, 4e-5, false));
  store::insert_calibration(db, run, "imu0", "m", record(1.5e-3, 4e-5, false));

  const UnitTrend t = unit_trend(db, "SN7");
  ASSERT_EQ(t.records.size(), 3u);
  EXPECT_LT(t.records[0].calibration, t.records[2].calibration);  // oldest first
  ASSERT_EQ(t.parameters.size(), 2u);
  const TrendParameter& bias = t.parameters[0];
  EXPECT_DOUBLE_EQ(*bias.values[0], 1.0e-3);
  EXPECT_DOUBLE_EQ(*bias.values[2], 1.5e-3);
  EXPECT_NEAR(bias.change, 0.5e-3, 1e-15);
  EXPECT_NEAR(bias.change_sigma, 5e-5, 1e-15);  // sqrt(3^2 + 4^2) e-5
  ASSERT_TRUE(bias.change_z.has_value());
  EXPECT_NEAR(*bias.change_z, 10.0, 1e-9);
  const TrendParameter& scale = t.parameters[1];
  EXPECT_FALSE(scale.values[1].has_value());  // not fitted in the later records
  EXPECT_FALSE(scale.change_z.has_value());   // one record: no change to weigh
  EXPECT_THROW(unit_trend(db, "SN-NONE"), core::InputError);
}

}  // namespace
}  // namespace calstand::analysis
