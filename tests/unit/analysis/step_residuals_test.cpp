// The step residuals a calibration record keeps for its certificate: written and read back
// exactly (a channel left out stays NaN), and a document that is not one refused by name.
#include "analysis/step_residuals.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "core/error.hpp"

namespace calstand::analysis {
namespace {

solver::FitResult two_steps() {
  solver::FitResult fit;
  for (std::size_t k = 0; k < 2; ++k) {
    solver::StepResidual s;
    s.index = 3 + 2 * k;
    s.label = k == 0 ? "z up" : "z down";
    s.residual << 1.0e-4 / 3.0, -2.5e-5, 7.0e-6 * static_cast<double>(k + 1), 1.0e-3 / 7.0, -3.0e-4,
        0.1 / 3.0;
    s.sigma << 1.1e-5, 1.2e-5, 1.3e-5, 2.1e-4, 2.2e-4, 2.3e-4;
    fit.steps.push_back(s);
  }
  // A gyro-only fit leaves the accelerometer channels out: NaN.
  fit.steps[1].residual(4) = std::numeric_limits<double>::quiet_NaN();
  return fit;
}

TEST(StepResiduals, RoundTripExactlyThroughTheirJsonText) {
  const solver::FitResult fit = two_steps();
  const nlohmann::json doc = nlohmann::json::parse(step_residuals_json(fit).dump());
  EXPECT_EQ(doc.at("format"), kStepResidualsFormat);
  EXPECT_TRUE(doc.at("steps")[1].at("residual")[4].is_null());
  const std::vector<solver::StepResidual> back = step_residuals_from_json(doc, "test");
  ASSERT_EQ(back.size(), 2u);
  for (std::size_t k = 0; k < 2; ++k) {
    EXPECT_EQ(back[k].index, fit.steps[k].index);
    EXPECT_EQ(back[k].label, fit.steps[k].label);
    for (Eigen::Index c = 0; c < 6; ++c) {
      if (std::isnan(fit.steps[k].residual(c))) {
        EXPECT_TRUE(std::isnan(back[k].residual(c)));
      } else {
        EXPECT_EQ(back[k].residual(c), fit.steps[k].residual(c)) << k << " " << c;
      }
      EXPECT_EQ(back[k].sigma(c), fit.steps[k].sigma(c)) << k << " " << c;
    }
  }
}

TEST(StepResiduals, AnythingElseIsRefusedNamingTheField) {
  nlohmann::json doc = step_residuals_json(two_steps());
  const auto where_of = [](const nlohmann::json& d) {
    try {
      step_residuals_from_json(d, "calibration 4");
    } catch (const core::InputError& e) {
      return e.where();
    }
    return std::string("accepted");
  };
  nlohmann::json other = doc;
  other["format"] = "calstand-step-residuals/0";
  EXPECT_EQ(where_of(other), "calibration 4: format");
  other = doc;
  other["steps"][1]["sigma"] = {1, 2, 3};
  EXPECT_EQ(where_of(other), "calibration 4: steps[1].sigma");
  other = doc;
  other["steps"][0]["residual"][2] = "x";
  EXPECT_EQ(where_of(other), "calibration 4: steps[0].residual[2]");
  other = doc;
  other["steps"][0].erase("index");
  EXPECT_EQ(where_of(other), "calibration 4: steps[0].index");
  EXPECT_EQ(where_of(doc), "accepted");
}

}  // namespace
}  // namespace calstand::analysis
