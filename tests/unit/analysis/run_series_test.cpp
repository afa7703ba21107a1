// A run's signal downsampled from the store, on a recorded run of the simulated station.
#include "analysis/run_series.hpp"

#include <gtest/gtest.h>

#include <algorithm>

#include "analysis/run_model.hpp"
#include "recorded_run.hpp"
#include "store/run_store.hpp"
#include "store/sample_reader.hpp"

namespace calstand::analysis {
namespace {

class RunSeriesTest : public ::testing::Test {
 protected:
  void SetUp() override {
    run_ = testing::record_run(db_file_.path(), "six-position", {"capture_s=10"}, 4);
  }
  std::int64_t total_samples() {
    store::Database db(db_file_.path());
    std::int64_t n = 0;
    for (const auto& step : store::RunStore(db).load_steps(run_)) {
      n += static_cast<std::int64_t>(store::read_samples(db, run_, step.index, "imu0").size());
    }
    return n;
  }
  testing::TempDatabase db_file_{"series"};
  std::int64_t run_ = 0;
};

TEST_F(RunSeriesTest, EverySampleIsCountedAndTheBucketsStayWithinMaxPoints) {
  store::Database db(db_file_.path());
  SeriesRequest request;
  request.signal = "az";
  request.max_points = 100;
  const RunSeries s = run_series(db, run_, request);
  EXPECT_EQ(s.unit, "m/s^2");
  EXPECT_EQ(s.device, "imu0");
  EXPECT_EQ(s.series.samples, total_samples());
  EXPECT_LE(s.series.t_s.size(), 100u);
  EXPECT_GT(s.series.t_s.size(), 50u);
  // z up and z down: gravity both ways.
  EXPECT_GT(*std::max_element(s.series.max.begin(), s.series.max.end()), 9.7);
  EXPECT_LT(*std::min_element(s.series.min.begin(), s.series.min.end()), -9.7);
  EXPECT_GE(s.series.t_s.front(), 0.0);
  const nlohmann::json j = to_json(s);
  EXPECT_EQ(j.at("signal"), "az");
  EXPECT_EQ(j.at("t_s").size(), j.at("min").size());
  EXPECT_EQ(j.at("samples"), s.series.samples);
}

TEST_F(RunSeriesTest, AWindowKeepsOnlyItsSamples) {
  store::Database db(db_file_.path());
  SeriesRequest all;
  all.signal = "temp_c";
  const RunSeries whole = run_series(db, run_, all);
  SeriesRequest window = all;
  window.from_s = 5.0;
  window.to_s = 15.0;
  const RunSeries part = run_series(db, run_, window);
  EXPECT_GT(part.series.samples, 0);
  EXPECT_LT(part.series.samples, whole.series.samples);
  EXPECT_GE(part.series.t_s.front(), 5.0);
  EXPECT_LE(part.series.t_s.back(), 15.0);
}

TEST_F(RunSeriesTest, TableSignalsFollowTheCommandedPositions) {
  store::Database db(db_file_.path());
  SeriesRequest request;
  request.signal = "table_outer_deg";
  const RunSeries s = run_series(db, run_, request);
  EXPECT_EQ(s.unit, "deg");
  // Outer 0, 180, -90, 90: the encoder reports 180 as -180 (angles in [-180, 180)).
  EXPECT_NEAR(*std::max_element(s.series.max.begin(), s.series.max.end()), 90.0, 0.5);
  EXPECT_NEAR(*std::min_element(s.series.min.begin(), s.series.min.end()), -180.0, 0.5);
}

TEST_F(RunSeriesTest, BadRequestsNameTheField) {
  store::Database db(db_file_.path());
  const auto where = [&](const SeriesRequest& r, std::int64_t run) -> std::string {
    try {
      run_series(db, run, r);
    } catch (const core::InputError& e) {
      return e.where();
    }
    return "no error";
  };
  SeriesRequest r;
  r.signal = "gw";
  EXPECT_EQ(where(r, run_), "signal");
  r.signal = "gx";
  r.max_points = 1;
  EXPECT_EQ(where(r, run_), "max_points");
  r.max_points = 10;
  r.from_s = 10.0;
  r.to_s = 5.0;
  EXPECT_EQ(where(r, run_), "from_s/to_s");
  r.from_s = 0.0;
  r.to_s = 5.0;
  EXPECT_EQ(where(r, 99), "run 99");
  EXPECT_THROW(run_series(db, 99, r), RunNotFound);
}

}  // namespace
}  // namespace calstand::analysis
