// The diagnose loop on runs without a table: simulated hand-held sessions with datasheet noise
// (ADIS16488-class: in-run bias instability, random walk, turn-on bias) imported as a user
// imports another tool's recording, with and without an effect the base model lacks.
#include "analysis/table_free_diagnose.hpp"

#include <gtest/gtest.h>

#include <algorithm>

#include "../tablefree/session_truth.hpp"
#include "core/error.hpp"
#include "imported_session.hpp"
#include "recorded_run.hpp"
#include "sim/spec_sheet.hpp"
#include "store/fit_history.hpp"

namespace calstand::analysis {
namespace {

using testing::import_session;

// A hand-held session of an ADIS16488-class unit at a decimated 400 Hz output (the sheet's
// noise densities; the output filter dropped above the new Nyquist frequency), optionally with
// a gyro g-sensitivity of a consumer-grade MEMS (the real Xsens recording shows ~0.1
// (deg/s)/g; the ADIS sheet says 0.009).
sim::SimSession hand_session(std::uint64_t seed, bool g_sensitive) {
  sim::HandSessionOptions options;
  options.poses = 24;
  options.imu.sample_rate_hz = 400.0;
  if (g_sensitive) {
    sim::ImuTruth truth =
        sim::truth_from_spec(*sim::builtin_spec("adis16488"), "adis16488", seed + 100);
    truth.gyro_g_sensitivity << 0.05, 0.01, -0.01, 0.0, -0.04, 0.015, 0.01, 0.0, 0.06;
    truth.gyro_scale_asymmetry.setZero();
    truth.gyro_quadratic.setZero();
    truth.accel_scale_asymmetry.setZero();
    truth.accel_quadratic.setZero();
    options.imu.truth = truth;
    options.imu.keep_unmodelled_terms = true;
  }
  return sim::simulate_hand_session(options, seed);
}

TEST(TableFreeDiagnose, AMissingGyroGSensitivityIsRankedFirstAndRecommended) {
  testing::TempDatabase file("tf-diagnose-g");
  store::Database db(file.path());
  const sim::SimSession session = hand_session(21, true);
  const std::int64_t run = import_session(session, db, "g");
  TableFreeFitRequest request;
  request.history_command = "diagnose";
  const TableFreeDiagnosis d = diagnose_table_free(db, run, request);
  ASSERT_FALSE(d.candidates.empty());
  EXPECT_EQ(d.candidates.front().term, "gyro_g_sensitivity");
  EXPECT_EQ(d.candidates.front().sensor, "gyro");
  EXPECT_EQ(d.candidates.front().added_parameters, 9);
  EXPECT_LT(d.candidates.front().p_value, 1e-3);
  EXPECT_LT(d.candidates.front().chi2_per_dof_after,
            0.5 * d.candidates.front().chi2_per_dof_before);
  EXPECT_EQ(d.recommended, "gyro_g_sensitivity") << to_json(d).at("candidates").dump(1);
  EXPECT_NE(d.advice.find("add gyro_g_sensitivity"), std::string::npos) << d.advice;
  // Where it fails: the turns (the accelerometers are fully modelled). Each sensor's z is
  // scaled by its own residuals' scatter, so a pose may still top the list by chance (with the
  // simulated flicker reaching short correlation times, pose 3 does at z -1.51 against the
  // worst turn's 1.41): the turns are among the first three.
  ASSERT_FALSE(d.worst.empty());
  const auto first = d.worst.begin();
  EXPECT_TRUE(std::any_of(first, first + std::min<std::ptrdiff_t>(3, std::ssize(d.worst)),
                          [](const TableFreeOutlier& w) { return w.unit == "deg"; }))
      << to_json(d).at("worst").dump(1);

  // The user adds it: the g-sensitivity found is the planted one (frame A), within its sigma.
  request.terms.gyro_g_sensitivity = true;
  const TableFreeFit after = table_free_fit(db, run, request);
  int checked = 0;
  for (const auto& e : after.gyro->parameters) {
    if (e.name.rfind("gyro_g_sensitivity.", 0) != 0) continue;
    EXPECT_NEAR(e.value, solver::testing::session_truth(session, e.name), 4.5 * e.sigma) << e.name;
    ++checked;
  }
  EXPECT_EQ(checked, 9);
  // Both fits are in the history, with the gravity direction after the turns falling.
  const auto history = store::fit_history(db, run);
  ASSERT_EQ(history.size(), 2u);
  EXPECT_EQ(history[0].command, "diagnose");
  ASSERT_TRUE(history[0].rms_turn_deg && history[1].rms_turn_deg);
  EXPECT_LT(*history[1].rms_turn_deg, 0.7 * *history[0].rms_turn_deg);
  EXPECT_FALSE(history[0].rms_gyro_dps.has_value());
  EXPECT_NE(history[1].model.find("gyro_g_sensitivity"), std::string::npos);
}

TEST(TableFreeDiagnose, NothingIsRecommendedWhenTheModelLacksNoEffect) {
  testing::TempDatabase file("tf-diagnose-none");
  store::Database db(file.path());
  for (std::uint64_t seed : {3, 8}) {
    const std::int64_t run =
        import_session(hand_session(seed, false), db, "none" + std::to_string(seed));
    const TableFreeDiagnosis d = diagnose_table_free(db, run, {});
    EXPECT_EQ(d.recommended, "") << "seed " << seed << ": " << d.advice;
    EXPECT_EQ(d.candidates.size(), 2u);
    for (const auto& c : d.candidates) EXPECT_GT(c.p_value, 1e-3) << c.term << " seed " << seed;
    // earth_rate is never offered: the heading is unknown.
    ASSERT_FALSE(d.untestable.empty());
    EXPECT_EQ(d.untestable.front().rfind("earth_rate", 0), 0u);
    const nlohmann::json j = to_json(d);
    EXPECT_EQ(j.at("method"), "gravity_norm");
    EXPECT_EQ(j.at("candidates").size(), 2u);
    EXPECT_TRUE(j.at("candidates")[0].contains("chi2_dof_after"));
  }
  EXPECT_TRUE(store::fit_history(db, 1).empty()) << "nothing recorded without a command";
}

// An LN200-class unit turned by hand, without any g-sensitivity: the vertical Earth rate,
// omega_ie sin(latitude) along gravity, looks exactly like an isotropic g-sensitivity to an
// integration that leaves it out (gyro_g_sensitivity was recommended at p ~1e-6). Modelled
// (the import carries the site's latitude), nothing is recommended, on the session
// `calstand sim-session --kind hand --model ln200` writes (30 poses, 400 Hz) and on a longer one
// (60 poses, 200 Hz), whose gyro triad relative to the accelerometers is then within 100 ppm and
// 1e-4 rad of the truth (30 poses leave the misalignments a sigma of about 3.5e-5 rad: the worst
// of six passes 1e-4 rad on some seeds).
TEST(TableFreeDiagnose, ATacticalGyroWithoutGSensitivityGetsNothingRecommended) {
  testing::TempDatabase file("tf-diagnose-ln200");
  store::Database db(file.path());
  for (const int poses : {30, 60}) {
    for (std::uint64_t seed : {1, 2, 3}) {
      SCOPED_TRACE(std::to_string(poses) + " poses, seed " + std::to_string(seed));
      sim::HandSessionOptions options;
      options.imu.spec = "ln200";
      options.poses = poses;
      if (poses > 30) options.imu.sample_rate_hz = 200.0;  // decimated: a shorter test
      const sim::SimSession session = sim::simulate_hand_session(options, seed);
      const std::int64_t run = import_session(
          session, db, "ln200-" + std::to_string(poses) + "-" + std::to_string(seed));
      const TableFreeDiagnosis d = diagnose_table_free(db, run, {});
      ASSERT_TRUE(d.fit.gyro);
      EXPECT_TRUE(d.fit.gyro->earth_rate_modelled);
      EXPECT_EQ(d.recommended, "") << to_json(d).at("candidates").dump(1);
      for (const auto& c : d.candidates) EXPECT_GT(c.p_value, 1e-3) << c.term;
      EXPECT_EQ(d.untestable.front().rfind("earth_rate: no candidate, modelled", 0), 0u);
      // The turns fit to their noise model.
      EXPECT_LT(d.fit.gyro->chi2_per_dof, 2.0);
      if (poses < 60) continue;
      int checked = 0;
      for (const auto& e : d.fit.gyro->parameters) {
        const double error = std::abs(e.value - solver::testing::session_truth(session, e.name));
        if (e.name.rfind("gyro_scale.", 0) == 0) {
          EXPECT_LT(error, 100.0) << e.name;
          ++checked;
        } else if (e.name.rfind("gyro_misalignment.", 0) == 0) {
          EXPECT_LT(error, 1e-4) << e.name;
          ++checked;
        }
      }
      EXPECT_EQ(checked, 9);
    }
  }
}

TEST(TableFreeDiagnose, AFerrarisSessionHasNoRedundancyForFurtherTerms) {
  testing::TempDatabase file("tf-diagnose-ferraris");
  store::Database db(file.path());
  const std::int64_t run = import_session(sim::simulate_ferraris_session({}, 4), db, "ferraris");
  const TableFreeDiagnosis d = diagnose_table_free(db, run, {});
  EXPECT_EQ(d.fit.method, "ferraris");
  EXPECT_TRUE(d.candidates.empty());
  EXPECT_EQ(d.untestable.size(), 3u);  // earth_rate and both optional terms
  EXPECT_NE(d.advice.find("Ferraris"), std::string::npos);
  TableFreeFitRequest request;
  request.terms.gyro_g_sensitivity = true;
  try {
    table_free_fit(db, run, request);
    FAIL() << "a Ferraris session took an optional term";
  } catch (const core::InputError& e) {
    EXPECT_EQ(e.where(), "model");
  }
}

}  // namespace
}  // namespace calstand::analysis
