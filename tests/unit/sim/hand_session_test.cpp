#include "sim/hand_session.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>

#include "core/rotation.hpp"
#include "sim/session_folder.hpp"
#include "sim/spec_sheet.hpp"

namespace calstand::sim {
namespace {

ImuTruth hand_test_truth(std::uint64_t seed) {
  return truth_from_spec(*builtin_spec("adis16488"), "adis16488", seed);
}

TEST(HandSession, TriadFrameTruthIsTheSameSensorInFrameA) {
  const ImuTruth t = hand_test_truth(3);
  const Eigen::Vector3d on_g(0.01, -0.02, 0.03), on_a(0.001, 0.002, -0.003);
  const TriadFrameTruth a = triad_frame_truth(t, on_g, on_a);
  const auto matrix = [](const Eigen::Vector3d& s, const Eigen::Matrix3d& m) {
    Eigen::Matrix3d T =
        Eigen::Matrix3d::Identity() + m - Eigen::Matrix3d(m.diagonal().asDiagonal());
    T.diagonal() += 1e-6 * s;
    return T;
  };
  const Eigen::Matrix3d TaB = matrix(t.accel_scale, t.accel_misalignment);
  const Eigen::Matrix3d TaA = matrix(a.accel_scale, a.accel_misalignment);
  const Eigen::Matrix3d Q = a.C_AB;
  EXPECT_LT((Q * Q.transpose() - Eigen::Matrix3d::Identity()).norm(), 1e-12);
  // Same readings for the same physical input: T_a^A Q f_B = T_a^B f_B, T_g^A Q w = T_g^B w.
  EXPECT_LT((TaA * Q - TaB).norm(), 1e-12);
  EXPECT_LT(
      (matrix(a.gyro_scale, a.gyro_misalignment) * Q - matrix(t.gyro_scale, t.gyro_misalignment))
          .norm(),
      1e-12);
  EXPECT_LT((a.gyro_g_sensitivity * Q - t.gyro_g_sensitivity).norm(), 1e-12);
  // The convention: accel misalignment lower triangular.
  EXPECT_EQ(a.accel_misalignment(0, 1), 0.0);
  EXPECT_EQ(a.accel_misalignment(0, 2), 0.0);
  EXPECT_EQ(a.accel_misalignment(1, 2), 0.0);
  EXPECT_LT((a.accel_bias - (t.accel_bias + on_a)).norm(), 1e-15);
  EXPECT_LT((a.gyro_bias - (t.gyro_bias + on_g)).norm(), 1e-15);
  EXPECT_EQ(a.parameters().size(), 24U + 9U);  // g-sensitivity listed when non-zero
  // accel_quadratic is carried as drawn, and listed when non-zero.
  ImuTruth q = t;
  q.accel_quadratic = Eigen::Vector3d(300.0, -200.0, 100.0);
  const TriadFrameTruth qa = triad_frame_truth(q, on_g, on_a);
  EXPECT_EQ(qa.accel_quadratic, q.accel_quadratic);
  EXPECT_EQ(qa.parameters().size(), 24U + 9U + 3U);
}

TEST(HandSession, ShapeOfASession) {
  HandSessionOptions o;
  o.imu.spec = "ln200";
  o.imu.sample_rate_hz = 200.0;
  o.poses = 15;
  o.initial_rest_s = 20.0;
  const SimSession s = simulate_hand_session(o, 5);
  EXPECT_EQ(s.kind, "hand");
  EXPECT_EQ(s.holds.size(), 16U);
  EXPECT_EQ(s.turns.size(), 15U);
  EXPECT_DOUBLE_EQ(s.holds[0].end_s, 20.0);
  EXPECT_DOUBLE_EQ(s.sample_rate_hz, 200.0);
  EXPECT_DOUBLE_EQ(s.gravity_mps2, 9.81744);
  for (std::size_t k = 1; k < s.samples.size(); ++k) {
    ASSERT_GT(s.samples[k].receive_time_s, s.samples[k - 1].receive_time_s);
  }
  int separated = 0;
  for (std::size_t k = 0; k < s.turns.size(); ++k) {
    const SessionTurn& t = s.turns[k];
    EXPECT_GE(t.end_s - t.start_s, o.turn_min_s - 1e-9);
    EXPECT_LE(t.peak_rate_dps, o.max_rate_dps + 1e-6);
    EXPECT_DOUBLE_EQ(t.start_s, s.holds[k].end_s);
    EXPECT_DOUBLE_EQ(t.end_s, s.holds[k + 1].start_s);
    const double hold = s.holds[k + 1].end_s - s.holds[k + 1].start_s;
    EXPECT_GE(hold, o.hold_min_s);
    EXPECT_LE(hold, o.hold_max_s);
    if (s.holds[k].up_A.dot(s.holds[k + 1].up_A) < std::cos(30.0 * core::kDegToRad)) ++separated;
  }
  EXPECT_GE(separated, 13);
  // Spread over the sphere: the gravity directions' scatter matrix is near I/3.
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const SessionHold& h : s.holds) scatter += h.up_A * h.up_A.transpose() / 16.0;
  EXPECT_LT((scatter - Eigen::Matrix3d::Identity() / 3.0).norm(), 0.12);
}

// With an ideal, noise-free IMU the gyro integrated over each turn carries the accelerometer's
// gravity direction of one pose into the next: the rates and forces of the motion agree.
TEST(HandSession, RatesAndForcesOfTheMotionAgree) {
  HandSessionOptions o;
  o.imu.truth = ImuTruth{};
  o.imu.truth->sample_rate_hz = 400.0;
  o.poses = 10;
  o.initial_rest_s = 5.0;
  o.tremor_deg = 0.0;
  const SimSession s = simulate_hand_session(o, 6);
  for (std::size_t k = 0; k < s.turns.size(); ++k) {
    const SessionHold& from = s.holds[k];
    const SessionHold& to = s.holds[k + 1];
    Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
    for (std::size_t i = from.end - 1; i < to.begin; ++i) {
      const double dt = s.samples[i + 1].receive_time_s - s.samples[i].receive_time_s;
      const Eigen::Vector3d th =
          0.5 * (s.samples[i].gyro_dps + s.samples[i + 1].gyro_dps) * core::kDegToRad * dt;
      if (th.norm() > 0.0)
        q = q * Eigen::Quaterniond(Eigen::AngleAxisd(th.norm(), th.normalized()));
    }
    const Eigen::Vector3d u0 = s.samples[from.end - 1].accel_mps2.normalized();
    const Eigen::Vector3d u1 = s.samples[to.begin].accel_mps2.normalized();
    const double err = std::acos(std::min(1.0, (q.conjugate() * u0).dot(u1))) * core::kRadToDeg;
    // The Earth rate (not removed here) moves it by at most 2 x 0.0042 deg/s x the turn.
    EXPECT_LT(err, 0.01 + 0.0084 * (s.turns[k].end_s - s.turns[k].start_s)) << "turn " << k;
    EXPECT_NEAR((q.toRotationMatrix() - from.C_LB.transpose() * to.C_LB).norm(), 0.0, 1e-3);
  }
}

TEST(HandSession, FerrarisSessionAndItsFolder) {
  FerrarisSessionOptions o;
  o.imu.spec = "adis16488";
  o.imu.sample_rate_hz = 100.0;
  const SimSession s = simulate_ferraris_session(o, 7);
  EXPECT_EQ(s.kind, "ferraris");
  ASSERT_EQ(s.holds.size(), 6U);
  ASSERT_EQ(s.turns.size(), 3U);
  ASSERT_EQ(s.step_labels.size(), 9U);
  EXPECT_EQ(s.step_labels[0], (std::pair<int, std::string>{1, "x_p"}));
  EXPECT_EQ(s.step_labels[8], (std::pair<int, std::string>{9, "z_rot"}));
  ASSERT_EQ(s.steps.size(), s.samples.size());
  const char* holds[] = {"x_p", "x_a", "y_p", "y_a", "z_p", "z_a"};
  for (int k = 0; k < 6; ++k) {
    const SessionHold& h = s.holds[static_cast<std::size_t>(k)];
    EXPECT_EQ(h.label, holds[k]);
    const double sign = k % 2 == 0 ? 1.0 : -1.0;
    // Within the placement tilt (and the triad's small rotation) of the nominal axis.
    EXPECT_GT(sign * h.up_A[k / 2], std::cos(4.0 * core::kDegToRad));
    for (std::size_t i = h.begin; i < h.end; ++i) EXPECT_EQ(s.steps[i], k + 1);
  }
  for (const SessionTurn& t : s.turns) EXPECT_DOUBLE_EQ(t.angle_deg, 360.0);

  const nlohmann::json meta = session_meta_json(s, {});
  EXPECT_EQ(meta["format"], "calstand-import/2");
  EXPECT_FALSE(meta.contains("table"));
  EXPECT_DOUBLE_EQ(meta["site"]["gravity_mps2"].get<double>(), s.gravity_mps2);
  EXPECT_EQ(meta["sections"]["1"],
            (nlohmann::json{{"label", "x_p"}, {"kind", "static"}, {"up", "+x"}}));
  EXPECT_EQ(meta["sections"]["2"]["up"], "-x");
  EXPECT_EQ(
      meta["sections"]["7"],
      (nlohmann::json{{"label", "x_rot"}, {"kind", "turn"}, {"axis", "+x"}, {"angle_deg", 360.0}}));
  EXPECT_EQ(meta["sections"].size(), 9U);

  const auto dir = std::filesystem::temp_directory_path() / "calstand_hand_session_test";
  std::filesystem::remove_all(dir);
  SessionFolderOptions fo;
  fo.counts = true;
  write_session_folder(s, dir, fo);
  std::ifstream csv(dir / "samples.csv");
  std::string header, first;
  std::getline(csv, header);
  std::getline(csv, first);
  EXPECT_EQ(header, "t,gx,gy,gz,ax,ay,az,temp_c,step");
  EXPECT_EQ(first.substr(first.rfind(',') + 1), "1");
  const nlohmann::json m = nlohmann::json::parse(std::ifstream(dir / "meta.json"));
  EXPECT_EQ(m["units"]["gyro"], "counts");
  EXPECT_DOUBLE_EQ(m["nominal"]["gyro"]["counts_per_dps"][0].get<double>(),
                   kSessionGyroCountsPerDps);
  const nlohmann::json truth = nlohmann::json::parse(std::ifstream(dir / "truth.json"));
  EXPECT_EQ(truth["parameters"].size(), 24U);
  EXPECT_EQ(truth["holds"].size(), 6U);
  EXPECT_TRUE(truth["holds"][0].contains("placement_tilt_deg"));
  std::filesystem::remove_all(dir);
}

// No poses: the initial rest alone, a record at rest (`calstand sim-session --kind static`).
TEST(HandSession, NoPosesIsTheInitialRestAlone) {
  HandSessionOptions o;
  o.poses = 0;
  o.initial_rest_s = 60.0;
  o.imu.spec = "adis16488";
  o.imu.sample_rate_hz = 100.0;
  const SimSession s = simulate_hand_session(o, 3);
  EXPECT_EQ(s.holds.size(), 1U);
  EXPECT_TRUE(s.turns.empty());
  ASSERT_GT(s.samples.size(), 5000U);
  EXPECT_NEAR(s.samples.back().receive_time_s - s.samples.front().receive_time_s, 60.0, 0.1);
  // At rest throughout: the gyros read the Earth rate and their errors, never a turn.
  double max_rate_dps = 0.0;
  for (const auto& x : s.samples) max_rate_dps = std::max(max_rate_dps, x.gyro_dps.norm());
  EXPECT_LT(max_rate_dps, 1.0);
}

TEST(HandSession, RefusesUnusableOptions) {
  HandSessionOptions o;
  o.poses = -1;
  EXPECT_THROW(simulate_hand_session(o, 1), std::invalid_argument);
  o.poses = 5;
  o.hold_min_s = 5.0;
  o.hold_max_s = 2.0;
  EXPECT_THROW(simulate_hand_session(o, 1), std::invalid_argument);
  HandSessionOptions u;
  u.imu.spec = "no-such-imu";
  EXPECT_THROW(simulate_hand_session(u, 1), std::invalid_argument);
}

}  // namespace
}  // namespace calstand::sim
