// calstand calibrate and apply as library calls: a record fitted on a run of the known IMU,
// applied to that run, leaves a run whose fitted errors are gone.
#include "analysis/calibrate.hpp"

#include <gtest/gtest.h>

#include "analysis/fit_request.hpp"
#include "analysis/run_model.hpp"
#include "recorded_run.hpp"
#include "store/calibrations.hpp"
#include "store/fit_history.hpp"
#include "store/run_store.hpp"

namespace calstand::analysis {
namespace {

constexpr const char* kAccelModel =
    "accel_bias,accel_scale,accel_misalignment,gyro_bias,earth_rate";

const solver::FittedParameter& parameter(const solver::FitResult& fit, const std::string& name) {
  for (const auto& p : fit.parameters) {
    if (p.name == name) return p;
  }
  throw std::runtime_error(name + " not fitted");
}

TEST(Calibrate, ARecordAppliedToItsRunRemovesTheErrorsItFitted) {
  testing::TempDatabase file("calibrate");
  const std::int64_t run = testing::record_run(file.path(), "six-position", {"capture_s=10"}, 3);
  store::Database db(file.path());
  const solver::Model model = solver::Model::parse(kAccelModel);
  const CalibrationOutcome c = calibrate_run(db, run, model, "");
  EXPECT_EQ(c.device, "imu0");
  EXPECT_EQ(c.steps, 6u);
  EXPECT_EQ(c.record.at("format"), "calstand-calibration/1");
  // Six 10 s captures are no noise record.
  EXPECT_FALSE(c.record.contains("noise") && !c.record.at("noise").is_null());
  const auto history = store::fit_history(db, run);
  ASSERT_EQ(history.size(), 1u);
  EXPECT_EQ(history[0].id, c.history_id);
  EXPECT_EQ(history[0].command, "calibrate");

  const std::int64_t id = store_calibration(db, c);
  const auto stored = store::calibrations_of_run(db, run);
  ASSERT_EQ(stored.size(), 1u);
  EXPECT_EQ(stored[0].id, id);
  EXPECT_EQ(stored[0].model, c.fit.model);
  EXPECT_EQ(default_calibration_file(run, "imu0"),
            "calibration-run" + std::to_string(run) + "-imu0.json");

  const solver::Calibration calibration = solver::read_calibration(c.record, "record");
  const ApplyOutcome applied = apply_calibration(db, run, "", calibration, "record.json");
  EXPECT_EQ(applied.source_run, run);
  EXPECT_EQ(applied.steps, 6u);
  EXPECT_FALSE(applied.outside_valid_range);
  EXPECT_LE(applied.min_temperature_c, applied.max_temperature_c);
  const auto corrected_run = store::RunStore(db).load_run(applied.run);
  EXPECT_EQ(corrected_run.summary.procedure_name, "corrected six-position");

  FitRequest again;
  again.model = model;
  const FitOutcome before = fit_request(db, run, again);
  const FitOutcome after = fit_request(db, applied.run, again);
  for (const char* name : {"accel_bias.x", "accel_bias.y", "accel_scale.x", "accel_scale.z"}) {
    const auto& b = parameter(before.fit, name);
    const auto& a = parameter(after.fit, name);
    EXPECT_NEAR(b.value, testing::known_imu_truth(name), 5.0 * b.sigma) << name;
    EXPECT_NEAR(a.value, 0.0, 5.0 * a.sigma) << name << " left after the correction";
  }
}

TEST(Calibrate, AnUnknownRunIsRunNotFound) {
  testing::TempDatabase file("calibrate-unknown");
  { store::Database create(file.path()); }
  store::Database db(file.path());
  EXPECT_THROW(calibrate_run(db, 5, solver::Model::parse(kAccelModel), ""), RunNotFound);
}

}  // namespace
}  // namespace calstand::analysis
