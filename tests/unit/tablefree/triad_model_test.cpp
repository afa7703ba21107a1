#include "tablefree/triad_model.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>

#include "core/error.hpp"

namespace calstand::solver {
namespace {

TEST(TriadModel, MatrixAndCorrectAreInverse) {
  TriadModel m;
  m.bias = {0.1, -0.2, 0.05};
  m.scale_ppm = {1000, -2000, 500};
  m.misalignment(0, 1) = 1e-3;
  m.misalignment(2, 0) = -2e-3;
  const Eigen::Vector3d f(1.0, -9.0, 3.0);
  const Eigen::Vector3d measured = m.matrix() * f + m.bias;
  EXPECT_LT((m.correct(measured) - f).norm(), 1e-12);
  const TriadModel back = TriadModel::from_matrix(m.matrix(), m.bias);
  EXPECT_LT((back.matrix() - m.matrix()).norm(), 1e-15);
}

TEST(TriadModel, LowerTriangularFrameFactorsAnyTriad) {
  Eigen::Matrix3d T;
  T << 1.003, 0.002, -0.004, 0.001, 0.998, 0.003, -0.002, 0.005, 1.01;
  const LowerTriangularFrame f = lower_triangular_frame(T);
  EXPECT_LT((f.L * f.Q - T).norm(), 1e-14);
  EXPECT_LT((f.Q * f.Q.transpose() - Eigen::Matrix3d::Identity()).norm(), 1e-14);
  EXPECT_GT(f.Q.determinant(), 0.0);
  // Upper part zero: accel_misalignment .xy .xz .yz by convention.
  EXPECT_EQ(f.L(0, 1), 0.0);
  EXPECT_EQ(f.L(0, 2), 0.0);
  EXPECT_EQ(f.L(1, 2), 0.0);
  for (int i = 0; i < 3; ++i) EXPECT_GT(f.L(i, i), 0.0);
  // Body x along accel x's sensitive axis (row 0 of T).
  EXPECT_LT((f.Q.row(0) - T.row(0).normalized()).norm(), 1e-12);
  EXPECT_THROW(lower_triangular_frame(Eigen::Matrix3d::Zero()), core::InputError);
}

TEST(TriadModel, UndeterminedColumnsFindsUnexcitedAndCollinear) {
  // Five columns: 0, 1 fine; 2 never excited; 3 and 4 identical (collinear).
  Eigen::MatrixXd J(20, 5);
  for (int k = 0; k < 20; ++k) {
    J(k, 0) = std::sin(k);
    J(k, 1) = std::cos(3.0 * k);
    J(k, 2) = 1e-9 * std::sin(2.0 * k);
    J(k, 3) = 0.5 + 0.1 * k;
    J(k, 4) = 0.5 + 0.1 * k;
  }
  const std::vector<int> u = undetermined_columns(J, Eigen::VectorXd::Ones(5));
  EXPECT_EQ(u, (std::vector<int>{2, 3, 4}));
  // Scaled by its natural unit, a small column is fine.
  Eigen::VectorXd natural = Eigen::VectorXd::Ones(5);
  J.col(3).setRandom();
  J.col(4) = 1e-6 * Eigen::VectorXd::LinSpaced(20, -1, 1).array().sin().matrix();
  natural[4] = 1e6;
  J.col(2).setRandom();
  EXPECT_TRUE(undetermined_columns(J, natural).empty());
}

TEST(TriadModel, StaticMeanSigmaGrowsWithCorrelation) {
  std::vector<core::ImuSample> white(4000), ar(4000);
  unsigned state = 12345;
  const auto uniform = [&] {
    state = state * 1664525u + 1013904223u;
    return (state >> 8) * (1.0 / 16777216.0) - 0.5;
  };
  double x = 0.0;
  for (std::size_t k = 0; k < white.size(); ++k) {
    const double e = uniform();
    white[k].accel_mps2 = Eigen::Vector3d::Constant(e);
    x = 0.9 * x + e;
    ar[k].accel_mps2 = Eigen::Vector3d::Constant(x);
  }
  const StaticMean w = static_mean(white, 0, white.size(), TriadSensor::kAccel);
  const StaticMean a = static_mean(ar, 0, ar.size(), TriadSensor::kAccel);
  EXPECT_NEAR(w.sigma_of_mean.x(), w.sample_sigma.x() / std::sqrt(4000.0),
              0.1 * w.sigma_of_mean.x());
  // AR(1) with phi 0.9: the mean's sigma is sqrt((1 + phi) / (1 - phi)) = 4.4 times the white
  // formula's.
  EXPECT_NEAR(a.sigma_of_mean.x() / (a.sample_sigma.x() / std::sqrt(4000.0)), 4.36, 0.5);
  EXPECT_THROW(static_mean(white, 5, 5, TriadSensor::kAccel), core::InputError);
}

TEST(TriadModel, NamesAndJson) {
  const auto names = triad_parameter_names("gyro");
  ASSERT_EQ(names.size(), 12U);
  EXPECT_EQ(names[0], "gyro_bias.x");
  EXPECT_EQ(names[11], "gyro_misalignment.zy");
  auto est = triad_estimates("accel", TriadModel{});
  est[6].status = EstimateStatus::kFixedByConvention;
  const nlohmann::json j = triad_estimates_to_json(est);
  ASSERT_EQ(j.size(), 12U);
  EXPECT_EQ(j[6]["status"], "fixed by convention");
  EXPECT_EQ(j[3]["unit"], "ppm");
  EXPECT_EQ(j[0]["unit"], "m/s^2");
}

}  // namespace
}  // namespace calstand::solver
