// Lot statistics on records with known numbers: each unit once (its newest record), the robust
// outlier rule, the individuals chart's limits and the yield.
#include "factory/lot.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "core/error.hpp"
#include "store/acceptances.hpp"
#include "store/calibrations.hpp"
#include "store/run_store.hpp"

namespace calstand::analysis {
namespace {

class LotTest : public ::testing::Test {
 protected:
  void SetUp() override {
    store::NewRun r;
    r.procedure_name = "six-position";
    r.procedure_text = "{}";
    r.parameters = nlohmann::json::object();
    r.station_snapshot = {{"name", "line-1"}};
    run_ = runs_.create_run(r);
    runs_.add_steps(run_, {{"capture", "z up", {{"duration_s", 1.0}}, "steps[0]"}});
  }
  std::int64_t calibrate(const std::string& serial, double bias_dps) {
    const nlohmann::json record = {
        {"device", {{"name", "imu0"}, {"model", "ln200"}, {"serial", serial}}},
        {"parameters",
         {{{"name", "gyro_bias.x"}, {"value", bias_dps}, {"sigma", 1e-4}, {"unit", "deg/s"}}}}};
    return store::insert_calibration(db_, run_, "imu0", "gyro_bias", record);
  }
  store::Database db_{":memory:"};
  store::RunStore runs_{db_};
  std::int64_t run_ = 0;
};

TEST_F(LotTest, EachUnitCountsOnceWithItsNewestRecordAndTheOddOneIsFlaggedEvenWhenItPasses) {
  // Seven units around 1e-3 deg/s with a spread of about 1e-4, one at 3e-3: 20 robust sigmas off.
  const std::vector<double> siblings = {1.00e-3, 1.10e-3, 0.92e-3, 1.05e-3, 0.97e-3, 1.02e-3};
  for (std::size_t i = 0; i < siblings.size(); ++i) {
    calibrate("SN" + std::to_string(i), i == 0 ? 9.0 : siblings[i]);  // SN0 recalibrated below
  }
  const std::int64_t odd = calibrate("SN-ODD", 3.0e-3);
  calibrate("SN0", siblings[0]);
  calibrate("", 5.0);  // nobody knows which unit: left out
  store::insert_acceptance(db_, odd, "datasheet", std::string(64, '0'), "pass", {});
  const std::int64_t failed = calibrate("SN-F", 1.01e-3);
  store::insert_acceptance(db_, failed, "datasheet", std::string(64, '0'), "fail", {});

  const LotStatistics lot = lot_statistics(db_, "");
  ASSERT_EQ(lot.units.size(), 8u);
  EXPECT_EQ(lot.records_without_serial, 1u);
  EXPECT_EQ(lot.passed, 1u);
  EXPECT_EQ(lot.failed, 1u);
  EXPECT_EQ(lot.not_judged, 6u);
  ASSERT_TRUE(lot.yield.has_value());
  EXPECT_DOUBLE_EQ(*lot.yield, 0.5);
  ASSERT_EQ(lot.parameters.size(), 1u);
  const LotParameter& p = lot.parameters[0];
  ASSERT_EQ(p.values.size(), 8u);
  // SN0's newest record (1e-3), not its first (9): it is not an outlier, SN-ODD is.
  ASSERT_EQ(p.outliers.size(), 1u);
  EXPECT_EQ(p.outliers[0].serial, "SN-ODD");
  EXPECT_EQ(p.outliers[0].verdict, "pass");
  EXPECT_GT(p.outliers[0].robust_z, kLotOutlierZ);

  // The statistics by hand.
  std::vector<double> all = {siblings.begin() + 1, siblings.end()};
  all.insert(all.end(), {3.0e-3, 1.00e-3, 1.01e-3});
  double mean = 0.0;
  for (double v : all) mean += v / static_cast<double>(all.size());
  EXPECT_NEAR(p.mean, mean, 1e-15);
  std::vector<double> sorted = all;
  std::sort(sorted.begin(), sorted.end());
  EXPECT_NEAR(p.median, 0.5 * (sorted[3] + sorted[4]), 1e-15);
  double moving = 0.0;
  for (std::size_t i = 1; i < p.values.size(); ++i)
    moving += std::abs(p.values[i] - p.values[i - 1]);
  EXPECT_NEAR(p.control_upper - p.mean, 3.0 * moving / 7.0 / 1.128, 1e-15);

  EXPECT_TRUE(lot_statistics(db_, "9999-01-01").units.empty());
  const nlohmann::json j = to_json(lot);
  EXPECT_EQ(j["parameters"][0]["outliers"][0]["serial"], "SN-ODD");
  EXPECT_EQ(j["verdicts"]["fail"], 1);
}

TEST_F(LotTest, TwoUnitsHaveNoSpreadToFlagAgainst) {
  calibrate("A", 1e-3);
  calibrate("B", 1.0);
  const LotStatistics lot = lot_statistics(db_, "");
  ASSERT_EQ(lot.parameters.size(), 1u);
  EXPECT_TRUE(lot.parameters[0].outliers.empty());
  EXPECT_FALSE(lot.yield.has_value());
}

// The start of a lot is compared with the records' times as text: only the forms that compare
// as they read are taken, and anything else is refused naming where it came from.
TEST_F(LotTest, ALotStartsAtADateOrATimeAndNothingElse) {
  calibrate("A", 1e-3);
  for (const char* since :
       {"", "2026-02-28", "2024-02-29", "2026-12-01T08:30", "2026-12-01T23:59:59"}) {
    EXPECT_NO_THROW(check_lot_since(since, "?since")) << since;
  }
  for (const char* since : {"yesterday", "2026-1-01", "2026/01/01", "2026-13-01", "2025-02-29",
                            "2026-01-01 08:30", "2026-01-01T24:00", "2026-01-01T08:30Z",
                            "2026-01-01T08:30:00.5", "-026-01-01", "2026-01-0x"}) {
    try {
      check_lot_since(since, "?since");
      ADD_FAILURE() << since << " was taken";
    } catch (const core::InputError& e) {
      EXPECT_EQ(e.where(), "?since") << since;
      EXPECT_NE(std::string(e.what()).find(since), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(lot_statistics(db_, "01.12.2026"), core::InputError);
  EXPECT_EQ(lot_statistics(db_, "2000-01-01T00:00").units.size(), 1u);
}

}  // namespace
}  // namespace calstand::analysis
