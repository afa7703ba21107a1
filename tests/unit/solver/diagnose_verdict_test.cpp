// When the best candidate "explains what it removes" though other effects remain: most of the
// whole excess over the noise, or most of the excess of the sensor that misfits most.
#include <gtest/gtest.h>

#include <cmath>

#include "solver/diagnose.hpp"

namespace calstand::solver {
namespace {

FitResult fit_with(double all, double gyro, double accel) {
  FitResult f;
  f.chi2_dof = all;
  f.chi2_dof_gyro = gyro;
  f.chi2_dof_accel = accel;
  return f;
}

Candidate candidate_with(double all, double gyro, double accel, double p = 1e-30) {
  Candidate c;
  c.p_value = p;
  c.chi2_dof_after = all;
  c.chi2_dof_after_gyro = gyro;
  c.chi2_dof_after_accel = accel;
  return c;
}

TEST(DiagnoseVerdict, MostOfTheWholeExcessDominates) {
  EXPECT_TRUE(best_candidate_dominates(fit_with(3.0, 3.0, 3.0), candidate_with(1.8, 1.8, 1.8)));
  EXPECT_FALSE(best_candidate_dominates(fit_with(3.0, 3.0, 3.0), candidate_with(2.2, 2.2, 2.2)));
}

TEST(DiagnoseVerdict, AGyroTermThatTakesTheWorstSensorMostOfTheWayDominates) {
  // The demo station's first round: both biases drift with temperature, the gyros misfit most,
  // and the gyro term removes 49 % of the whole excess but 79 % of the gyros'.
  const FitResult demo = fit_with(2.76, 3.21, 2.31);
  EXPECT_TRUE(best_candidate_dominates(demo, candidate_with(1.89, 1.47, 2.31)));
  // Without a strong F-test it explains nothing.
  EXPECT_FALSE(best_candidate_dominates(demo, candidate_with(1.89, 1.47, 2.31, 1e-3)));
}

TEST(DiagnoseVerdict, ATermOnTheSensorThatMisfitsLessDoesNotDominateByItsOwnShare) {
  // The accelerometers misfit most; an accelerometer-only share is not asked of a gyro term,
  // and a gyro term that removes the whole small gyro excess is not most of the problem.
  const FitResult f = fit_with(3.0, 1.4, 4.6);
  EXPECT_FALSE(best_candidate_dominates(f, candidate_with(2.8, 1.0, 4.6)));
  EXPECT_TRUE(best_candidate_dominates(f, candidate_with(2.4, 1.4, 2.6)));
}

TEST(DiagnoseVerdict, OneSensorFittedFallsBackToTheWholeExcess) {
  const double nan = std::nan("");
  EXPECT_FALSE(best_candidate_dominates(fit_with(3.0, 3.0, nan), candidate_with(2.2, 1.2, nan)));
}

}  // namespace
}  // namespace calstand::solver
