#include "tablefree/pose_noise.hpp"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace calstand::solver {
namespace {

// Thirty poses of 5 s, 8 s apart, their gravity directions drawn on the sphere, white
// variance 1 (the residuals' unit), and a Jacobian of nine columns like the gravity norm's
// (bias u_i, scale u_i^2, misalignment u_i u_j).
struct PoseLayout {
  std::vector<PoseSpan> poses;
  Eigen::MatrixXd jacobian;
};

PoseLayout make_setup(std::mt19937_64& rng) {
  std::normal_distribution<double> n01;
  PoseLayout s;
  const int n = 30;
  s.jacobian.resize(n, 9);
  for (int k = 0; k < n; ++k) {
    const Eigen::Vector3d u = Eigen::Vector3d(n01(rng), n01(rng), n01(rng)).normalized();
    s.poses.push_back({8.0 * k, 8.0 * k + 5.0, u, 1.0});
    s.jacobian.row(k) << u.x(), u.y(), u.z(), u.x() * u.x(), u.y() * u.y(), u.z() * u.z(),
        u.x() * u.y(), u.x() * u.z(), u.y() * u.z();
  }
  return s;
}

Eigen::VectorXd draw(const Eigen::MatrixXd& sigma, std::mt19937_64& rng) {
  std::normal_distribution<double> n01;
  Eigen::VectorXd z(sigma.rows());
  for (Eigen::Index i = 0; i < z.size(); ++i) z[i] = n01(rng);
  return Eigen::LLT<Eigen::MatrixXd>(sigma).matrixL() * z;
}

TEST(PoseNoise, WhiteResidualsStayWhite) {
  std::mt19937_64 rng(1);
  int white = 0;
  for (int trial = 0; trial < 20; ++trial) {
    const PoseLayout s = make_setup(rng);
    const PoseNoise noise =
        estimate_pose_noise(s.poses, draw(Eigen::MatrixXd::Identity(30, 30), rng), s.jacobian);
    EXPECT_TRUE(noise.estimated);
    EXPECT_EQ(noise.dof, 21);
    if (noise.wander.kind == WanderKind::kNone && noise.extra_variance == 0.0) ++white;
  }
  EXPECT_GE(white, 15);
}

TEST(PoseNoise, FindsASharedGaussMarkovWander) {
  std::mt19937_64 rng(2);
  PoseNoise truth;
  truth.wander.kind = WanderKind::kGaussMarkov;
  truth.wander.sigma = 5.0;
  truth.wander.tau_s = 60.0;
  std::vector<double> ratios;
  for (int trial = 0; trial < 20; ++trial) {
    const PoseLayout s = make_setup(rng);
    const PoseNoise noise =
        estimate_pose_noise(s.poses, draw(truth.covariance(s.poses), rng), s.jacobian);
    EXPECT_NE(noise.wander.kind, WanderKind::kNone) << noise.description;
    EXPECT_NE(noise.description.find("estimated by REML from 30 residuals"), std::string::npos)
        << noise.description;
    ratios.push_back(noise.pose_sigma / truth.wander.sigma);
  }
  std::sort(ratios.begin(), ratios.end());
  EXPECT_GT(ratios[10], 0.5);  // the median pose sigma, against the process's sigma
  EXPECT_LT(ratios[10], 2.0);
}

TEST(PoseNoise, CovarianceSharesTheWanderAlongTheDirections) {
  std::mt19937_64 rng(3);
  const PoseLayout s = make_setup(rng);
  PoseNoise noise;
  noise.wander.kind = WanderKind::kGaussMarkov;
  noise.wander.sigma = 2.0;
  noise.wander.tau_s = 30.0;
  const Eigen::MatrixXd C = noise.covariance(s.poses);
  EXPECT_LT((C - C.transpose()).norm(), 1e-12);
  const PoseSpan& a = s.poses[3];
  const PoseSpan& b = s.poses[4];
  EXPECT_NEAR(C(3, 4),
              a.direction.dot(b.direction) *
                  noise.wander.interval_mean_covariance(a.start_s, a.end_s, b.start_s, b.end_s),
              1e-12);
  EXPECT_NEAR(C(3, 3),
              1.0 + noise.wander.interval_mean_covariance(a.start_s, a.end_s, a.start_s, a.end_s),
              1e-12);
  PoseNoise extra;
  extra.extra_variance = 0.5;
  const Eigen::MatrixXd E = extra.covariance(s.poses);
  EXPECT_DOUBLE_EQ(E(0, 0), 1.5);
  EXPECT_DOUBLE_EQ(E(0, 1), 0.0);
}

TEST(PoseNoise, TooFewResidualsKeepWhiteAndSayWhy) {
  std::mt19937_64 rng(4);
  PoseLayout s = make_setup(rng);
  s.poses.resize(14);
  const Eigen::MatrixXd J = s.jacobian.topRows(14);
  const PoseNoise noise =
      estimate_pose_noise(s.poses, draw(Eigen::MatrixXd::Identity(14, 14), rng), J);
  EXPECT_FALSE(noise.estimated);
  EXPECT_EQ(noise.dof, 5);
  EXPECT_NE(noise.description.find("5 degrees of freedom"), std::string::npos) << noise.description;
  const nlohmann::json j = pose_noise_to_json(noise);
  EXPECT_EQ(j["kind"], "none");
  EXPECT_EQ(j["estimated"], false);
}

}  // namespace
}  // namespace calstand::solver
