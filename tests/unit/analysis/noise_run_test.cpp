// The wander of a unit measured on a static run, for the fit and diagnosis of another run of the
// same unit (`calstand fit|diagnose --noise-run`): each identified term mapped to the process the
// step means carry, and a recorded static run's model reaching the fit's weights.
#include "analysis/noise_run.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <ostream>
#include <string>
#include <vector>

#include "../solver/warm_up_campaign.hpp"
#include "analysis/calibrate.hpp"
#include "analysis/fit_request.hpp"
#include "core/error.hpp"
#include "imported_session.hpp"
#include "recorded_run.hpp"
#include "solver/custom_term.hpp"
#include "solver/diagnose.hpp"
#include "static_run_wander.hpp"

namespace calstand::analysis {
namespace {

TEST(SegmentRecord, ConsecutiveSegmentsOfTheLengthAskedAndNoShortTail) {
  solver::RunData record;
  store::StepData capture;
  capture.step.label = "static";
  for (int i = 0; i < 1050; ++i) {  // 10 Hz for 104.9 s
    core::ImuSample s;
    s.receive_time_s = 50.0 + 0.1 * i;
    capture.samples.push_back(s);
  }
  record.steps.push_back(capture);
  const solver::RunData segments = segment_record(record, 10.0);
  ASSERT_EQ(segments.steps.size(), 10U);  // the last 4.9 s are too short to count
  for (std::size_t k = 0; k < segments.steps.size(); ++k) {
    const auto& seg = segments.steps[k].samples;
    EXPECT_EQ(seg.size(), 100U) << k;
    EXPECT_NEAR(seg.front().receive_time_s, 50.0 + 10.0 * static_cast<double>(k), 1e-9) << k;
    EXPECT_EQ(segments.steps[k].step.index, k);
  }
  EXPECT_THROW(segment_record(solver::RunData{}, 10.0), core::InputError);
}

// A Gauss-Markov bias of a MEMS-class unit (10 deg/h, 300 s on the gyros; 700 ug, 300 s on the
// accelerometers) measured from 3 h at rest, for a thermal campaign of 60 s steps: a wander
// on every channel of about the simulated size, and a record too short refused naming it.
TEST(WanderOfStaticRecord, MeasuresTheUnitsGaussMarkovBiasAndRefusesAShortRecord) {
  const sim::ImuTruth truth = solver::testing::unit_of("mems", 31);
  const solver::RunData campaign = solver::testing::warm_up_run(truth, 0.0, 600.0, 0.0, 32);
  const solver::KnownWander w = calstand::testing::static_run_wander(truth, 3.0, 33, campaign);
  EXPECT_NE(w.source.find("a simulated static run of 3 h"), std::string::npos) << w.source;
  EXPECT_NE(w.source.find("means of 60 s"), std::string::npos) << w.source;
  for (std::size_t c = 0; c < w.wander.size(); ++c) {
    SCOPED_TRACE(c);
    const solver::WanderModel& m = w.wander[c];
    ASSERT_NE(m.kind, solver::WanderKind::kNone);
    solver::WanderModel truth_wander;
    truth_wander.kind = solver::WanderKind::kGaussMarkov;
    truth_wander.sigma =
        c < 3 ? truth.gyro_noise.gauss_markov_sigma[0] : truth.accel_noise.gauss_markov_sigma[0];
    truth_wander.tau_s = truth.gyro_noise.gauss_markov_tau_s;
    // Half the mean square difference of two adjacent means of T (a constant offset, which the
    // bias takes, cancels): within a factor 3 of the truth's at a step and at ten, whatever
    // process the likelihood chose (3 h of 60 s means seldom tell this Gauss-Markov from a
    // flicker, whose curve is flat: 2.5 times the truth's at 60 s, 0.8 times at 600 s).
    for (double T : {60.0, 600.0}) {
      const auto allan = [T](const solver::WanderModel& x) {
        return x.interval_mean_covariance(0.0, T, 0.0, T) -
               x.interval_mean_covariance(0.0, T, T, 2.0 * T);
      };
      EXPECT_GT(allan(m), allan(truth_wander) / 3.0) << T;
      EXPECT_LT(allan(m), allan(truth_wander) * 3.0) << T;
    }
  }
  solver::testing::SimStep rest;
  rest.duration_s = 600.0;
  const solver::RunData short_record = solver::testing::simulate_run(truth, {rest}, 34);
  try {
    wander_of_static_record(short_record, campaign, "static run 9");
    FAIL() << "10 min at rest gave a wander";
  } catch (const core::InputError& e) {
    EXPECT_EQ(e.where(), "static run 9");
    EXPECT_NE(std::string(e.what()).find("at least 20"), std::string::npos) << e.what();
  }
}

// A recorded static run of the known IMU (white noise only) weighs a six-position run of the same
// unit: the fit's noise model says where its wander came from, and a static run too short for a
// noise model is refused naming the run.
class NoiseRunTest : public ::testing::Test {
 protected:
  calstand::testing::TempDatabase db_file_{"noise-run"};
};

TEST_F(NoiseRunTest, TheStaticRunsWanderWeighsTheFitAndTheDiagnosis) {
  const std::int64_t still = calstand::testing::record_run(
      db_file_.path(), "static-allan", {"duration_s=900", "soak_s=1", "warmup_s=1"}, 21);
  const std::int64_t run =
      calstand::testing::record_run(db_file_.path(), "six-position", {"capture_s=10"}, 21);
  store::Database db(db_file_.path());
  FitRequest request;
  request.model = model_from_lists({"gyro_bias", "accel_bias"}, {});
  request.noise_run = still;
  const FitOutcome fit = fit_request(db, run, request);
  EXPECT_NE(fit.fit.noise.method.find(fmt::format("static run {}", still)), std::string::npos)
      << fit.fit.noise.method;
  for (const auto& ch : fit.fit.noise.channels) {
    EXPECT_TRUE(ch.determined);
    EXPECT_NE(ch.source.find(fmt::format("static run {}", still)), std::string::npos) << ch.source;
  }
  const DiagnoseOutcome d = diagnose_request(db, run, request);
  EXPECT_NE(d.diagnosis.fit.noise.method.find(fmt::format("static run {}", still)),
            std::string::npos)
      << d.diagnosis.fit.noise.method;

  // `calibrate --noise-run`: the record's parameters are weighed the same way, and it says so.
  const solver::Model model = solver::Model::parse("gyro_bias,accel_bias");
  const CalibrationOutcome own = calibrate_run(db, run, model, "");
  const CalibrationOutcome known = calibrate_run(db, run, model, "", {}, still);
  const std::string method = known.record["fit"]["noise_model"].value("method", "");
  EXPECT_NE(method.find(fmt::format("static run {}", still)), std::string::npos) << method;
  EXPECT_EQ(own.record["fit"]["noise_model"].value("method", "").find("static run"),
            std::string::npos);
  EXPECT_EQ(known.fit.parameters.size(), fit.fit.parameters.size());
  for (std::size_t i = 0; i < known.fit.parameters.size(); ++i) {
    EXPECT_DOUBLE_EQ(known.fit.parameters[i].sigma, fit.fit.parameters[i].sigma)
        << known.fit.parameters[i].name;
  }

  const std::int64_t short_still = calstand::testing::record_run(
      db_file_.path(), "static-allan", {"duration_s=60", "soak_s=1", "warmup_s=1"}, 21);
  request.noise_run = short_still;
  try {
    fit_request(db, run, request);
    FAIL() << "a 60 s static run gave a wander";
  } catch (const core::InputError& e) {
    EXPECT_EQ(e.where(), fmt::format("noise run {}", short_still)) << e.what();
  }
}

// A record at rest made by another tool, imported without a table or a site (an ADIS16488-class
// unit's, from sim/hand_session.hpp), serves as well: its wander needs neither. A run without a
// table is refused, its poses being weighed by their own noise.
TEST_F(NoiseRunTest, ARecordImportedWithoutATableServesAndARunWithoutOneIsRefused) {
  const std::int64_t run =
      calstand::testing::record_run(db_file_.path(), "six-position", {"capture_s=10"}, 21);
  store::Database db(db_file_.path());
  sim::HandSessionOptions at_rest;
  at_rest.poses = 0;
  at_rest.initial_rest_s = 600.0;
  at_rest.imu.sample_rate_hz = 200.0;
  const std::int64_t still = calstand::testing::import_session(
      sim::simulate_hand_session(at_rest, 5), db, "noise-run-at-rest");
  FitRequest request;
  request.model = model_from_lists({"gyro_bias", "accel_bias"}, {});
  request.noise_run = still;
  const FitOutcome fit = fit_request(db, run, request);
  EXPECT_NE(fit.fit.noise.method.find(fmt::format("static run {}", still)), std::string::npos)
      << fit.fit.noise.method;
  for (int c = solver::kGx; c <= solver::kGz; ++c) {
    // The sheet's bias instability (5.1 deg/h floor) is what 600 s at rest shows of it.
    EXPECT_NE(fit.fit.noise.channels[static_cast<std::size_t>(c)].wander.kind,
              solver::WanderKind::kNone)
        << c;
  }

  sim::HandSessionOptions turned;
  turned.poses = 12;
  turned.imu.sample_rate_hz = 200.0;
  const std::int64_t hand = calstand::testing::import_session(sim::simulate_hand_session(turned, 6),
                                                              db, "noise-run-hand");
  try {
    calibrate_run(db, hand, solver::Model::parse("gyro_bias,accel_bias"), "", {}, still);
    FAIL() << "a run without a table took a static run's wander";
  } catch (const core::InputError& e) {
    EXPECT_EQ(e.where(), "--noise-run") << e.what();
  }
}

// Issue 28's hardest case: a warm-up of 5 step means' noise on a MEMS-class gyro (a Gauss-Markov
// bias 3 times its white noise at 60 s), which the run's own wander hides more often than not
// (docs/guide-loop.md). With the wander a 3 h static run of the same unit measured, the diagnosis
// finds it, and the same unit without one gets nothing. Seeds in order, not chosen; the rates
// over many are the bench's (`calstand_warm_up_detection_bench SEEDS mems known`).
struct KnownWanderCase {
  const char* noise;
  std::uint64_t seed;
  double tau_s;
  double static_capture_s;
  double times;  ///< the warm-up over a step mean's noise
};

void PrintTo(const KnownWanderCase& c, std::ostream* os) {
  *os << fmt::format("{} seed {} tau {:g} s capture {:g} s {:g}x", c.noise, c.seed, c.tau_s,
                     c.static_capture_s, c.times);
}

class WarmUpWithTheWanderKnown : public ::testing::TestWithParam<KnownWanderCase> {};

TEST_P(WarmUpWithTheWanderKnown, IsFoundAndTheCleanRunGetsNothing) {
  const KnownWanderCase c = GetParam();
  const sim::ImuTruth truth = solver::testing::unit_of(c.noise, c.seed);
  const solver::Model model = solver::Model::parse(solver::testing::true_terms(truth));
  const double amplitude = c.times * solver::testing::step_mean_noise_dps(truth, c.seed + 1);
  const solver::RunData warm =
      solver::testing::warm_up_run(truth, c.static_capture_s, c.tau_s, amplitude, c.seed + 2);
  solver::DiagnoseOptions options;
  options.noise.known_wander = calstand::testing::static_run_wander(truth, 3.0, c.seed + 3, warm);
  const solver::Diagnosis d = solver::diagnose(warm, model, {}, options);
  EXPECT_FALSE(d.explained) << d.advice;
  ASSERT_FALSE(d.suggestions.empty()) << d.advice;
  const std::string& top = d.suggestions.front().custom;
  EXPECT_NE(top.find("=gyro"), std::string::npos) << top;
  const auto slash = top.find("elapsed/");
  ASSERT_NE(slash, std::string::npos) << top;
  const double tau = std::stod(top.substr(slash + 8));
  EXPECT_GT(tau, c.tau_s / 2.0) << top;
  EXPECT_LT(tau, 2.0 * c.tau_s) << top;
  const solver::Model with = model.with_custom(solver::parse_custom_term(top, "--custom " + top));
  const solver::Diagnosis after = solver::diagnose(warm, with, {}, options);
  EXPECT_LE(after.fit.chi2_dof, 1.3);
  EXPECT_TRUE(after.suggestions.empty()) << after.advice;
  EXPECT_EQ(after.recommended, "") << after.advice;

  const solver::RunData clean =
      solver::testing::warm_up_run(truth, c.static_capture_s, c.tau_s, 0.0, c.seed + 2);
  options.noise.known_wander = calstand::testing::static_run_wander(truth, 3.0, c.seed + 3, clean);
  const solver::Diagnosis none = solver::diagnose(clean, model, {}, options);
  EXPECT_TRUE(none.suggestions.empty()) << none.advice;
}

INSTANTIATE_TEST_SUITE_P(Mems5x, WarmUpWithTheWanderKnown,
                         ::testing::Values(KnownWanderCase{"mems", 101, 600.0, 0.0, 5.0},
                                           KnownWanderCase{"mems", 102, 900.0, 1800.0, 5.0}));
// A white-noise unit, whose static run shows no wander, with a slow warm-up (1800 s) and no
// capture: a temperature order alone takes the warm-up's offset on the first plateau (BIC -1394
// against the known noise, where the decay beyond every catalogue term gives -228), so the
// catalogue is weighed by what it adds once the decay is there (suggest.cpp). The bench's case
// (seed 7097 of `calstand_warm_up_detection_bench 4 white known 10`), which that rule turned
// from missed to found.
INSTANTIATE_TEST_SUITE_P(SlowOnWhite, WarmUpWithTheWanderKnown,
                         ::testing::Values(KnownWanderCase{"white", 7097, 1800.0, 0.0, 10.0}));

}  // namespace
}  // namespace calstand::analysis
