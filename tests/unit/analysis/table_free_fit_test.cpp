// A run without a table end to end: a simulated session written as a calstand-import/2 folder
// (no table columns), imported by the store, calibrated by analysis::table_free_fit() as
// `calstand fit` does, against the session's truth in the accelerometer-triad frame.
#include "analysis/table_free_fit.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "../tablefree/session_truth.hpp"
#include "analysis/run_model.hpp"
#include "imported_session.hpp"
#include "noise/run_noise.hpp"
#include "recorded_run.hpp"
#include "sim/hand_session.hpp"

namespace calstand::analysis {
namespace {

using testing::import_session;

// Every estimated parameter of `estimates` within 4.5 sigma of the session's truth (the sigma
// of a wandering-bias sensor's estimates is honest only to a factor near one).
void expect_session_truth(const sim::SimSession& s,
                          const std::vector<solver::TriadEstimate>& estimates, const char* prefix,
                          bool counts, bool earth_rate_modelled = false) {
  int checked = 0;
  for (const auto& e : estimates) {
    if (e.status != solver::EstimateStatus::kEstimated || e.name.rfind(prefix, 0) != 0) continue;
    double truth = solver::testing::session_truth(s, e.name, earth_rate_modelled);
    // Counts are written whole: the nominal conversion's rounding is part of the bias.
    if (counts && e.name.find("_bias.") != std::string::npos) continue;
    EXPECT_NEAR(e.value, truth, 4.5 * e.sigma) << e.name << " sigma " << e.sigma;
    ++checked;
  }
  EXPECT_GE(checked, counts ? 6 : 9) << prefix;  // accel: 9 estimated, gyro 12
}

TEST(TableFreeFit, AHandHeldSessionImportedWithoutATableRecoversTheTruth) {
  testing::TempDatabase file("table-free-hand");
  store::Database db(file.path());
  sim::HandSessionOptions options;
  options.poses = 24;
  const sim::SimSession session = sim::simulate_hand_session(options, 7);
  const std::int64_t run = import_session(session, db, "hand", false);

  EXPECT_TRUE(needs_table_free_fit(db, run));
  const TableFreeFit fit = table_free_fit(db, run, {});
  EXPECT_EQ(fit.method, "gravity_norm");
  ASSERT_TRUE(fit.poses && fit.accel && fit.gyro);
  // The detector finds the rest and every pose the session held.
  EXPECT_EQ(fit.poses->detection.intervals.size(), session.holds.size());
  EXPECT_TRUE(fit.poses->detection.intervals.front().initial_rest);
  expect_session_truth(session, fit.accel->parameters, "accel_", false);
  // The import carries the site's latitude: the Earth rate is modelled, and the gyro bias is
  // the rest mean less the Earth rate there.
  ASSERT_TRUE(fit.gyro->earth_rate_modelled);
  expect_session_truth(session, fit.gyro->parameters, "gyro_", false, true);
  EXPECT_LT(fit.accel->rms_residual_mg, 1.0);

  const nlohmann::json j = to_json(fit);
  EXPECT_EQ(j.at("method"), "gravity_norm");
  EXPECT_TRUE(j.at("accel").contains("parameters"));
  EXPECT_TRUE(j.at("gyro").contains("parameters"));
  EXPECT_EQ(j.at("poses").at("detection").at("intervals").size(), session.holds.size());
}

// The Earth rate comes from the run's site latitude (the import's site.latitude_deg): with
// it the fit models the Earth rate and says so; a run that carries none (a station snapshot
// without it) is fitted as before, the rest's Earth rate left in the gyro bias, with a note.
TEST(TableFreeFit, TheEarthRateComesFromTheSiteLatitudeOrIsLeftOutWithANote) {
  testing::TempDatabase file("table-free-latitude");
  store::Database db(file.path());
  sim::HandSessionOptions options;
  options.poses = 12;
  options.imu.sample_rate_hz = 200.0;
  options.imu.latitude_deg = -33.9;
  const sim::SimSession session = sim::simulate_hand_session(options, 13);
  const std::int64_t run = import_session(session, db, "latitude");

  const TableFreeFit with = table_free_fit(db, run, {});
  ASSERT_TRUE(with.gyro);
  EXPECT_TRUE(with.gyro->earth_rate_modelled);
  ASSERT_TRUE(with.latitude_deg.has_value());
  EXPECT_DOUBLE_EQ(*with.latitude_deg, -33.9);
  EXPECT_DOUBLE_EQ(with.gyro->latitude_deg, -33.9);
  EXPECT_TRUE(to_json(with).at("earth_rate_modelled").get<bool>());
  EXPECT_NE(with.gyro->summary.find("-33.90 deg"), std::string::npos) << with.gyro->summary;

  db.sql().exec(
      "UPDATE runs SET station_snapshot = json_remove(station_snapshot, '$.site.latitude_deg')");
  const TableFreeFit without = table_free_fit(db, run, {});
  ASSERT_TRUE(without.gyro);
  EXPECT_FALSE(without.latitude_deg.has_value());
  EXPECT_FALSE(without.gyro->earth_rate_modelled);
  EXPECT_FALSE(to_json(without).at("earth_rate_modelled").get<bool>());
  ASSERT_FALSE(without.notes.empty());
  EXPECT_NE(without.notes.back().find("no site latitude"), std::string::npos);
  EXPECT_NE(without.gyro->summary.find("latitude is not known"), std::string::npos);
  // As before: the bias is the rest mean, the Earth rate there included.
  expect_session_truth(session, without.gyro->parameters, "gyro_", false, false);
  expect_session_truth(session, with.gyro->parameters, "gyro_", false, true);
}

TEST(TableFreeFit, OperatorIntervalsReplaceTheDetectorAndAreCheckedAgainstTheRecording) {
  testing::TempDatabase file("table-free-given");
  store::Database db(file.path());
  sim::HandSessionOptions options;
  options.poses = 12;
  const sim::SimSession session = sim::simulate_hand_session(options, 3);
  const std::int64_t run = import_session(session, db, "given", true);
  TableFreeFitRequest request;
  for (const auto& h : session.holds)
    request.intervals_s.emplace_back(h.start_s + 0.3, h.end_s - 0.3);
  const TableFreePoses poses = table_free_poses(db, run, request);
  EXPECT_TRUE(poses.given);
  ASSERT_EQ(poses.detection.intervals.size(), session.holds.size());
  EXPECT_TRUE(poses.detection.intervals.front().initial_rest);
  const TableFreeFit fit = table_free_fit(db, run, request);
  expect_session_truth(session, fit.accel->parameters, "accel_", true);

  request.intervals_s = {{1e6, 1e6 + 5}};
  try {
    table_free_poses(db, run, request);
    FAIL() << "an interval outside the recording was taken";
  } catch (const core::InputError& e) {
    EXPECT_EQ(e.where(), "--static-intervals[0]");
  }
}

TEST(TableFreeFit, FewerThanNinePosesAreRefusedNamingTheCount) {
  testing::TempDatabase file("table-free-few");
  store::Database db(file.path());
  sim::HandSessionOptions options;
  options.poses = 5;
  const std::int64_t run = import_session(sim::simulate_hand_session(options, 5), db, "few", false);
  try {
    table_free_fit(db, run, {});
    FAIL() << "six poses were calibrated";
  } catch (const core::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("9"), std::string::npos) << e.what();
  }
}

TEST(TableFreeFit, ALabelledFerrarisSessionIsFittedByFerrarisWithThePlacementEstimated) {
  testing::TempDatabase file("table-free-ferraris");
  store::Database db(file.path());
  const sim::SimSession session = sim::simulate_ferraris_session({}, 11);
  const std::int64_t run = import_session(session, db, "ferraris", false);
  const TableFreeFit fit = table_free_fit(db, run, {});
  ASSERT_EQ(fit.method, "ferraris");
  ASSERT_TRUE(fit.ferraris);
  EXPECT_TRUE(fit.ferraris->placement_estimated);
  EXPECT_LT(fit.ferraris->accel_chi2_per_dof, fit.ferraris->accel_chi2_per_dof_naive);
  EXPECT_EQ(to_json(fit).at("ferraris").at("method"), "ferraris");
}

TEST(TableFreeFit, ARunWithATableIsNotFittedThisWay) {
  testing::TempDatabase file("table-free-table");
  const std::int64_t run = testing::record_run(file.path(), "two-position", {"capture_s=2"}, 3);
  store::Database db(file.path());
  EXPECT_FALSE(needs_table_free_fit(db, run));
  EXPECT_THROW(table_free_fit(db, run, {}), core::InputError);
  EXPECT_THROW(needs_table_free_fit(db, run + 10), RunNotFound);
}

TEST(TableFreeFit, AHandTurnedRecordingIsNoStaticStepForTheNoiseAnalysis) {
  testing::TempDatabase file("table-free-noise");
  store::Database db(file.path());
  sim::HandSessionOptions options;
  options.poses = 10;
  options.imu.sample_rate_hz = 200.0;
  const std::int64_t run = import_session(sim::simulate_hand_session(options, 2), db, "noise");
  try {
    solver::choose_noise_step(db, run, std::nullopt);
    FAIL() << "a hand-turned recording was taken for a static capture";
  } catch (const core::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("recorded without a table turn"), std::string::npos)
        << e.what();
  }
  EXPECT_EQ(solver::choose_noise_step(db, run, 0), 0u) << "the step given is analysed";
}

}  // namespace
}  // namespace calstand::analysis
