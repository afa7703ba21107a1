// What a specification can name: glob patterns, the catalogue's parameters, the noise figures
// (whose units must stay those the noise analysis writes into records) and the fit figures.
#include "factory/acceptance_names.hpp"

#include <gtest/gtest.h>

#include <set>

#include "noise/run_noise.hpp"

namespace calstand::analysis {
namespace {

TEST(GlobMatch, StarMatchesAnyRunIncludingDots) {
  EXPECT_TRUE(glob_match("gyro_bias.*", "gyro_bias.x"));
  EXPECT_FALSE(glob_match("gyro_bias.*", "gyro_bias"));
  EXPECT_FALSE(glob_match("gyro_bias.*", "accel_bias.x"));
  EXPECT_TRUE(glob_match("*_misalignment.*", "accel_misalignment.zy"));
  EXPECT_TRUE(glob_match("*_misalignment.*", "gyro_misalignment.xy"));
  EXPECT_FALSE(glob_match("*_misalignment.*", "gyro_scale.x"));
  EXPECT_TRUE(glob_match("*", "anything.at.all"));
  EXPECT_TRUE(glob_match("gyro*x", "gyro_scale.x"));
  EXPECT_FALSE(glob_match("gyro*x", "gyro_scale.y"));
  EXPECT_TRUE(glob_match("a**b", "ab"));
  EXPECT_TRUE(glob_match("gyro_bias.x", "gyro_bias.x"));
  EXPECT_FALSE(glob_match("gyro_bias.x", "gyro_bias.xy"));
  EXPECT_FALSE(glob_match("", "x"));
  EXPECT_TRUE(glob_match("*.x*", "gyro_temp_bias.x12"));
}

TEST(AcceptanceNames, TheCatalogueParametersCarryTheContractUnits) {
  std::set<std::string> names;
  for (const auto& p : catalogue_parameters()) {
    names.insert(p.name);
    if (p.name == "gyro_bias.x") {
      EXPECT_EQ(p.unit, "deg/s");
    }
    if (p.name == "accel_quadratic.z") {
      EXPECT_EQ(p.unit, "ug/g^2");
    }
    if (p.name == "table_tilt.east") {
      EXPECT_EQ(p.unit, "rad");
    }
  }
  EXPECT_TRUE(names.count("gyro_temp_bias.z9"));
  EXPECT_TRUE(names.count("gyro_g_sensitivity.zz"));
  EXPECT_FALSE(names.count("gyro_misalignment.xx"));
  // 3 + 3 + 6 + 3 + 3 + 9 + 27 + 3 (gyro), 3 + 3 + 6 + 3 + 3 + 27 + 3 + 3 (accel), 2 (tilt).
  EXPECT_EQ(names.size(), 57u + 51u + 2u);
}

TEST(AcceptanceNames, NoiseUnitsAreThoseOfTheDatasheetFigures) {
  // The record's noise block is written from solver::datasheet_figures(); a spec's unit is
  // checked against this table, so the two must agree figure by figure.
  const solver::NoiseTerms terms{};
  for (const bool gyro : {true, false}) {
    const auto figures = solver::datasheet_figures(terms, gyro);
    for (const auto& n : noise_names()) {
      if (n.gyro != gyro) continue;
      bool found = false;
      for (const auto& f : figures) {
        if (f.name != n.figure) continue;
        found = true;
        EXPECT_EQ(f.unit, n.unit) << n.name;
      }
      EXPECT_TRUE(found) << n.name << " reads a figure the noise analysis does not write";
    }
  }
  EXPECT_EQ(noise_quantities().size(), 3 * noise_names().size());
}

const nlohmann::json kNamesRecord = nlohmann::json::parse(R"js({
  "parameters": [{"name": "gyro_bias.x", "value": 0.002, "sigma": 0.0001, "unit": "deg/s"}],
  "unidentifiable": [{"name": "gyro_temp_bias.x1", "reason": "one temperature"}],
  "fit": {"chi2_dof": null, "dof": 0, "residual_rms": {"gyro": 0.001, "accel": 0.0002}},
  "noise": {"step": 3, "duration_s": 600, "channels": {
    "gx": [{"name": "angle_random_walk", "value": 0.1, "sigma": 0.002, "unit": "deg/sqrt(h)", "resolved": true},
           {"name": "bias_instability_min_coefficient", "value": 0.5, "sigma": null, "unit": "deg/h", "resolved": true},
           {"name": "rate_random_walk", "value": 0.0, "sigma": 0.0, "unit": "deg/h/sqrt(h)", "resolved": false}],
    "ax": [{"name": "velocity_random_walk", "value": 0.03, "sigma": 0.0004, "unit": "m/s/sqrt(h)", "resolved": true}]}}
})js");

TEST(AcceptanceNames, ARecordsValuesByName) {
  const auto params = record_parameters(kNamesRecord);
  ASSERT_EQ(params.size(), 2u);
  EXPECT_EQ(params[0].name, "gyro_bias.x");
  EXPECT_DOUBLE_EQ(params[0].value, 0.002);
  EXPECT_DOUBLE_EQ(*params[0].sigma, 0.0001);
  EXPECT_FALSE(params[1].present);
  EXPECT_EQ(params[1].unit, "deg/s/degC^k");
  EXPECT_NE(params[1].note.find("one temperature"), std::string::npos);

  const auto noise = record_noise(kNamesRecord);
  ASSERT_EQ(noise.size(), 4u);
  EXPECT_EQ(noise[0].name, "gyro_arw.x");
  EXPECT_DOUBLE_EQ(*noise[0].sigma, 0.002);
  EXPECT_EQ(noise[1].name, "gyro_bias_instability.x");
  EXPECT_FALSE(noise[1].sigma);  // read off the curve: no sigma
  EXPECT_EQ(noise[2].name, "gyro_rrw.x");
  EXPECT_FALSE(noise[2].note.empty());  // not resolved
  EXPECT_EQ(noise[3].name, "accel_vrw.x");

  const auto fit = record_fit(kNamesRecord);  // chi2_dof null: not listed
  ASSERT_EQ(fit.size(), 2u);
  EXPECT_EQ(fit[0].name, "rms_gyro");
  EXPECT_EQ(fit[0].unit, "deg/s");
  EXPECT_EQ(fit[1].name, "rms_accel");
  EXPECT_TRUE(record_noise(nlohmann::json::object()).empty());
}

}  // namespace
}  // namespace calstand::analysis
