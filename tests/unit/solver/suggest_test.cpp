// Custom terms the diagnosis builds from the signals when no catalogue term explains the
// residual (issue 13, "Suggestions it has tried"): simulated campaigns with one effect outside
// the catalogue, under white and datasheet (LN200-class) noise. The suggestion must be the
// effect's form (one axis when one channel has it, `{axis}` when each follows its own axis, a
// transient with its time constant), parse as `--custom` text, and give through fit_run (the
// path of `calstand fit --custom`) exactly the chi2/dof it reports, at the noise floor. Without an
// effect outside the catalogue nothing is suggested, even when the search is forced.
#include "solver/suggest.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <random>
#include <set>

#include "sim/noise.hpp"
#include "sim/spec_sheet.hpp"
#include "sim_run.hpp"
#include "solver/diagnose.hpp"
#include "solver/noise_estimate.hpp"

namespace calstand::solver {
namespace {

using testing::kBaseModel;
using testing::SimStep;
using testing::true_terms;

/// A thermal calibration as a station records it (the library's order): per plateau a soak
/// (unrecorded), six static positions and turns about every body axis at three rates in both
/// directions (one whole revolution each), with the moves between steps unrecorded.
std::vector<SimStep> station_campaign(double first_soak_s = 1800.0, double soak_s = 1800.0) {
  std::vector<SimStep> steps;
  for (double temp : {-20.0, 25.0, 70.0}) {
    bool first = true;
    for (auto s : testing::six_positions(temp, 20.0)) {
      s.gap_before_s = first ? (steps.empty() ? first_soak_s : soak_s) : 8.0;
      first = false;
      steps.push_back(s);
    }
    for (double rate : {30.0, 90.0, 200.0}) {
      for (auto s : testing::rate_steps({rate}, temp, 360.0 / rate)) {
        s.gap_before_s = 4.0;
        steps.push_back(s);
      }
    }
  }
  return steps;
}

/// White noise and classical errors (bias, scale factor, misalignment) of LN200 size.
sim::ImuTruth white_unit(std::uint64_t seed) {
  sim::ImuTruth t = testing::white_noise_truth(2e-3, 5e-4, 100.0);
  sim::NormalSource n(seed);
  testing::draw_classical_errors(t, n);
  return t;
}

/// Adds `effect(signals)` (gyro x y z, accel x y z) to every sample, with the signals as a
/// custom term sees them.
void add_effect(RunData& data, const std::function<Vector6d(const Signals&)>& effect) {
  const SignalBuilder build(data.setup, true);
  const double start = data.steps.front().samples.front().receive_time_s;
  for (auto& step : data.steps) {
    const std::vector<double> rates = step_temperature_rates(step.samples);
    for (std::size_t i = 0; i < step.samples.size(); ++i) {
      core::ImuSample& s = step.samples[i];
      const Vector6d e = effect(build(s, step.table[i], rates[i], s.receive_time_s - start));
      s.gyro_dps += e.head<3>();
      s.accel_mps2 += e.tail<3>();
    }
  }
}

/// Diagnosis options that search custom terms whatever the catalogue does.
DiagnoseOptions search_forced() {
  DiagnoseOptions o;
  o.custom_search = CustomSearch::kAlways;
  return o;
}

void print(const Diagnosis& d) {
  std::printf("chi2/dof %.3f, best catalogue %s (%.3f); %s\n", d.fit.chi2_dof,
              d.candidates.empty() ? "-" : d.candidates.front().term.c_str(),
              d.candidates.empty() ? 0.0 : d.candidates.front().chi2_dof_after,
              d.custom_summary.c_str());
  for (const auto& s : d.suggestions) {
    std::printf("  %s: chi2/dof %.4f, delta BIC %.1f (+%d), held out %.3f -> %.3f (%s)\n    %s\n",
                s.custom.c_str(), s.chi2_dof_after, s.delta_bic, s.added_parameters,
                s.held_out_chi2_dof_before, s.held_out_chi2_dof_after, s.held_out.c_str(),
                s.explanation.c_str());
  }
}

/// The suggestion parses as `--custom` text and gives through fit_run (what `calstand fit
/// --custom` calls) exactly the chi2/dof it reports, at the noise floor; it earned its
/// parameters and held on held-out data.
void expect_as_reported(const RunData& data, const Model& model, const Suggestion& s,
                        const std::string& held_out_by = "temperature plateaus") {
  const CustomTermSpec spec = parse_custom_term(s.custom, "--custom " + s.custom);
  EXPECT_EQ(spec.text(), s.custom);
  const FitResult fit = fit_run(data, model.with_custom(spec));
  EXPECT_NEAR(fit.chi2_dof, s.chi2_dof_after, 1e-6 * s.chi2_dof_after) << s.custom;
  EXPECT_LE(fit.chi2_dof, 1.3) << s.custom;
  EXPECT_LT(s.delta_bic, -10.0) << s.custom;
  EXPECT_LT(s.held_out_chi2_dof_after, s.held_out_chi2_dof_before) << s.custom;
  EXPECT_NE(s.held_out.find(held_out_by), std::string::npos) << s.held_out;
  EXPECT_FALSE(s.explanation.empty());
}

/// Diagnoses `data` with `model`: the catalogue must not explain the residual, and the first
/// suggestion must be `expected` (SENSOR[.AXES]:EXPRESSION, whatever its name).
Diagnosis expect_suggestion(const RunData& data, const Model& model, const std::string& expected,
                            const std::string& held_out_by = "temperature plateaus") {
  const Diagnosis d = diagnose(data, model);
  print(d);
  EXPECT_FALSE(d.explained) << d.advice;
  EXPECT_TRUE(d.custom_searched);
  if (d.suggestions.empty()) {
    ADD_FAILURE() << "nothing suggested: " << d.advice;
    return d;
  }
  const Suggestion& top = d.suggestions.front();
  EXPECT_EQ(top.custom.substr(top.custom.find('=') + 1), expected) << top.custom;
  EXPECT_LT(top.chi2_dof_after, d.fit.chi2_dof);
  expect_as_reported(data, model, top, held_out_by);
  // The advice names it as a ready --custom argument, and no catalogue term is recommended.
  EXPECT_NE(d.advice.find("--custom '" + top.custom + "'"), std::string::npos) << d.advice;
  EXPECT_EQ(d.recommended, "");
  return d;
}

// --- (a) One channel follows a signal: the term acts on that axis alone -----------------------

Vector6d gz_on_force_z_squared(const Signals& s) {
  Vector6d e = Vector6d::Zero();
  e[kGz] = 3e-4 * s.force_mps2.z() * s.force_mps2.z();
  return e;
}

TEST(Suggest, OneChannelFollowingAForceSquaredGetsAOneAxisTerm) {
  RunData data = testing::simulate_run(white_unit(1), station_campaign(), 11);
  add_effect(data, gz_on_force_z_squared);
  expect_suggestion(data, Model::parse(kBaseModel), "gyro.z:force_z^2");
}

TEST(Suggest, OneChannelFollowingAForceSquaredUnderDatasheetNoise) {
  const sim::ImuTruth truth = testing::datasheet_unit("ln200", 2);
  RunData data = testing::simulate_run(truth, station_campaign(), 12);
  add_effect(data, gz_on_force_z_squared);
  expect_suggestion(data, Model::parse(true_terms(truth)), "gyro.z:force_z^2");
}

TEST(Suggest, WithOnePlateauTheHeldOutCheckIsByFoldsOfSteps) {
  std::vector<SimStep> steps;
  for (const SimStep& s : station_campaign()) {
    if (s.temperature_c == 25.0) steps.push_back(s);
  }
  RunData data = testing::simulate_run(white_unit(3), steps, 13);
  add_effect(data, gz_on_force_z_squared);
  expect_suggestion(data, Model::parse(kBaseModel), "gyro.z:force_z^2",
                    "folds of interleaved steps");
}

// --- (b) Each channel follows its own axis's signal: the {axis} form --------------------------

Vector6d gyro_on_own_force_squared(const Signals& s) {
  Vector6d e = Vector6d::Zero();
  e.head<3>() = Eigen::Vector3d(5e-5, -4e-5, 6e-5).cwiseProduct(s.force_mps2.cwiseAbs2());
  return e;
}

TEST(Suggest, EachAxisFollowingItsOwnForceSquaredGetsTheAxisForm) {
  RunData data = testing::simulate_run(white_unit(4), station_campaign(), 14);
  add_effect(data, gyro_on_own_force_squared);
  expect_suggestion(data, Model::parse(kBaseModel), "gyro:force_{axis}^2");
}

TEST(Suggest, EachAxisFollowingItsOwnForceSquaredUnderDatasheetNoise) {
  const sim::ImuTruth truth = testing::datasheet_unit("ln200", 5);
  RunData data = testing::simulate_run(truth, station_campaign(), 15);
  add_effect(data, gyro_on_own_force_squared);
  expect_suggestion(data, Model::parse(true_terms(truth)), "gyro:force_{axis}^2");
}

// --- (c) A warm-up transient: exp(-elapsed/tau) with tau found -------------------------------

/// Accelerometer bias settling after power-on (2 to 3 mg) with a 900 s time constant: the run
/// starts recording at power-on and soaks 10 minutes at each new plateau, so the transient
/// reaches into all three.
Vector6d accel_warm_up(const Signals& s) {
  Vector6d e = Vector6d::Zero();
  e.tail<3>() = Eigen::Vector3d(2e-2, -1.5e-2, 2.5e-2) * std::exp(-s.elapsed_s / 900.0);
  return e;
}

double tau_of(const std::string& custom) {
  const auto slash = custom.find("elapsed/");
  return slash == std::string::npos ? 0.0 : std::stod(custom.substr(slash + 8));
}

void expect_transient(const RunData& data, const Model& model) {
  const Diagnosis d = diagnose(data, model);
  print(d);
  EXPECT_FALSE(d.explained) << d.advice;
  ASSERT_FALSE(d.suggestions.empty()) << d.advice;
  const Suggestion& top = d.suggestions.front();
  EXPECT_NE(top.custom.find("=accel"), std::string::npos) << top.custom;
  EXPECT_NE(top.custom.find(":exp(-elapsed/"), std::string::npos) << top.custom;
  const double tau = tau_of(top.custom);
  EXPECT_GT(tau, 900.0 / 1.5) << top.custom;
  EXPECT_LT(tau, 900.0 * 1.5) << top.custom;
  // A transient in elapsed time extrapolates in time, not in temperature: held out by folds of
  // interleaved steps (issue 28), not by plateaus.
  expect_as_reported(data, model, top, "folds of interleaved steps");
}

TEST(Suggest, AWarmUpTransientGetsExpOfElapsedWithItsTimeConstant) {
  RunData data = testing::simulate_run(white_unit(6), station_campaign(0.0, 600.0), 16);
  add_effect(data, accel_warm_up);
  expect_transient(data, Model::parse(kBaseModel));
}

TEST(Suggest, AWarmUpTransientUnderDatasheetNoise) {
  const sim::ImuTruth truth = testing::datasheet_unit("ln200", 2);
  RunData data = testing::simulate_run(truth, station_campaign(0.0, 600.0), 17);
  add_effect(data, accel_warm_up);
  expect_transient(data, Model::parse(true_terms(truth)));
}

// --- (d) Nothing outside the catalogue: nothing suggested -----------------------------------

TEST(Suggest, NothingIsSuggestedWhenTheModelFits) {
  for (std::uint64_t seed : {7, 8}) {
    const RunData data = testing::simulate_run(white_unit(seed), station_campaign(), 10 + seed);
    const Diagnosis d = diagnose(data, Model::parse(kBaseModel));
    EXPECT_TRUE(d.explained) << d.advice;
    EXPECT_TRUE(d.suggestions.empty());
    // Forced, the search finds nothing either: every guard holds on noise alone.
    const Diagnosis forced = diagnose(data, Model::parse(kBaseModel), {}, search_forced());
    print(forced);
    EXPECT_TRUE(forced.custom_searched);
    EXPECT_GT(forced.custom_forms_tried, 200);
    EXPECT_TRUE(forced.suggestions.empty()) << forced.suggestions.front().custom;
    EXPECT_NE(forced.custom_summary.find("none of the"), std::string::npos)
        << forced.custom_summary;
  }
}

TEST(Suggest, NothingIsSuggestedUnderDatasheetNoiseWithTheTrueModel) {
  for (std::uint64_t seed : {3, 4}) {
    const sim::ImuTruth truth = testing::datasheet_unit("ln200", seed);
    const RunData data = testing::simulate_run(truth, station_campaign(), 20 + seed);
    const Diagnosis forced = diagnose(data, Model::parse(true_terms(truth)), {}, search_forced());
    print(forced);
    EXPECT_TRUE(forced.suggestions.empty()) << forced.suggestions.front().custom;
  }
}

TEST(Suggest, ACatalogueEffectIsNotDisguisedAsACustomTerm) {
  // A g-sensitivity the model lacks: the catalogue has it, so no custom term may claim it.
  sim::ImuTruth truth = white_unit(9);
  truth.gyro_g_sensitivity(0, 2) = 3e-3;
  truth.gyro_g_sensitivity(2, 1) = -2e-3;
  const RunData data = testing::simulate_run(truth, station_campaign(), 19);
  const Diagnosis d = diagnose(data, Model::parse(kBaseModel), {}, search_forced());
  print(d);
  ASSERT_FALSE(d.candidates.empty());
  EXPECT_EQ(d.candidates.front().term, "gyro_g_sensitivity");
  EXPECT_EQ(d.recommended, "gyro_g_sensitivity");
  EXPECT_TRUE(d.explained);
  EXPECT_TRUE(d.suggestions.empty()) << d.suggestions.front().custom;
}

TEST(Suggest, JsonListsTheSuggestionsBestFirst) {
  RunData data = testing::simulate_run(white_unit(1), station_campaign(), 11);
  add_effect(data, gz_on_force_z_squared);
  const nlohmann::json j = diagnosis_to_json(diagnose(data, Model::parse(kBaseModel)));
  ASSERT_TRUE(j.contains("suggestions"));
  ASSERT_FALSE(j["suggestions"].empty());
  double previous = -1e300;
  for (const auto& s : j["suggestions"]) {
    for (const char* key : {"custom", "chi2_dof_after", "delta_bic", "p_value", "added_parameters",
                            "held_out", "explanation"}) {
      EXPECT_TRUE(s.contains(key)) << key;
    }
    EXPECT_TRUE(s["held_out"].contains("chi2_dof_after"));
    EXPECT_GE(s["delta_bic"].get<double>(), previous);
    previous = s["delta_bic"].get<double>();
  }
  EXPECT_TRUE(j["custom_search"]["ran"].get<bool>());
  EXPECT_GT(j["custom_search"]["forms_tried"].get<int>(), 200);
  EXPECT_FALSE(j["explained"].get<bool>());
}

}  // namespace
}  // namespace calstand::solver
