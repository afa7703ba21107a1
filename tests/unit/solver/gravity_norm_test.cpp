#include "solver/gravity_norm.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "core/error.hpp"
#include "session_truth.hpp"
#include "sim/hand_session.hpp"
#include "solver/static_detector.hpp"

namespace calstand::solver {
namespace {

sim::SimSession norm_session(const char* spec, std::uint64_t seed, int poses = 20) {
  sim::HandSessionOptions o;
  o.imu.spec = spec;
  o.imu.sample_rate_hz = 200.0;
  o.poses = poses;
  o.initial_rest_s = 30.0;
  return sim::simulate_hand_session(o, seed);
}

GravityNormResult norm_fit(const sim::SimSession& s) {
  GravityNormOptions o;
  o.gravity_mps2 = s.gravity_mps2;
  return calibrate_accel_gravity_norm(s.samples, detect_static_intervals(s.samples, {}).intervals,
                                      o);
}

// ADIS16488- and LN200-class sessions with their datasheet noise (white, bias instability or
// Gauss-Markov, turn-on bias), hand tremor, lever arm and jittered time stamps.
TEST(GravityNorm, RecoversTheTruthWithinItsSigmas) {
  std::vector<testing::Pull> all;
  for (const char* spec : {"adis16488", "ln200"}) {
    for (std::uint64_t seed : {11, 12, 13}) {
      SCOPED_TRACE(std::string(spec) + " seed " + std::to_string(seed));
      const sim::SimSession s = norm_session(spec, seed);
      const GravityNormResult r = norm_fit(s);
      EXPECT_TRUE(r.converged);
      EXPECT_EQ(r.poses.size(), s.holds.size());
      EXPECT_TRUE(r.undetermined.empty());
      EXPECT_EQ(r.dof, static_cast<int>(r.poses.size()) - 9);
      for (const testing::Pull& p : testing::session_pulls(s, r.parameters)) {
        EXPECT_LT(std::abs(p.pull), 4.0) << p.name;
        all.push_back(p);
      }
      for (const TriadEstimate& e : r.parameters) {
        if (e.status != EstimateStatus::kEstimated) continue;
        if (e.unit == "ppm") {
          EXPECT_TRUE(e.sigma > 3.0 && e.sigma < 300.0) << e.name << " " << e.sigma;
        }
        if (e.unit == "rad") {
          EXPECT_TRUE(e.sigma > 3e-6 && e.sigma < 1e-3) << e.name << " " << e.sigma;
        }
      }
      // The residual in words, in mg, per pose.
      EXPECT_GT(r.rms_residual_mg, 0.005);
      EXPECT_LT(r.rms_residual_mg, 0.5);
      EXPECT_NE(r.summary.find("mg"), std::string::npos);
    }
  }
  ASSERT_EQ(all.size(), 6U * 9U);
  const double rms = testing::rms_pull(all);
  EXPECT_GT(rms, 0.6);
  EXPECT_LT(rms, 1.5);
}

TEST(GravityNorm, ConventionFixesTheUpperMisalignments) {
  const GravityNormResult r = norm_fit(norm_session("ln200", 14));
  ASSERT_EQ(r.parameters.size(), 12U);
  for (const TriadEstimate& e : r.parameters) {
    const bool upper = e.name == "accel_misalignment.xy" || e.name == "accel_misalignment.xz" ||
                       e.name == "accel_misalignment.yz";
    EXPECT_EQ(e.status == EstimateStatus::kFixedByConvention, upper) << e.name;
    if (upper) {
      EXPECT_EQ(e.value, 0.0);
      EXPECT_EQ(e.sigma, 0.0);
    }
  }
  EXPECT_EQ(r.accel.misalignment(0, 1), 0.0);
  EXPECT_EQ(r.accel.misalignment(1, 2), 0.0);
}

TEST(GravityNorm, RefusesFewerThanNinePoses) {
  const sim::SimSession s = norm_session("adis16488", 15, 7);  // the rest and 7 poses
  try {
    norm_fit(s);
    FAIL() << "8 poses were accepted";
  } catch (const core::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("9 static poses are needed"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("found 8"), std::string::npos) << e.what();
  }
}

TEST(GravityNorm, NamesWhatPosesThatNeverTipYCannotDetermine) {
  sim::HandSessionOptions o;
  o.imu.spec = "adis16488";
  o.imu.sample_rate_hz = 200.0;
  o.poses = 20;
  o.initial_rest_s = 30.0;
  o.single_turn_axis = Eigen::Vector3d::UnitY();  // gravity stays in the x-z plane
  const sim::SimSession s = sim::simulate_hand_session(o, 16);
  const GravityNormResult r = norm_fit(s);
  std::vector<std::string> u = r.undetermined;
  std::sort(u.begin(), u.end());
  EXPECT_EQ(u, (std::vector<std::string>{"accel_bias.y", "accel_misalignment.yx",
                                         "accel_misalignment.zy", "accel_scale.y"}));
  EXPECT_NE(r.summary.find("do not determine accel_bias.y"), std::string::npos) << r.summary;
  for (const TriadEstimate& e : r.parameters) {
    if (std::find(u.begin(), u.end(), e.name) != u.end()) {
      EXPECT_EQ(e.status, EstimateStatus::kUndetermined);
      EXPECT_EQ(e.sigma, 0.0);
    }
  }
  // What the poses do determine is still right.
  for (const testing::Pull& p : testing::session_pulls(s, r.parameters)) {
    EXPECT_LT(std::abs(p.pull), 4.0) << p.name;
  }
}

TEST(GravityNorm, ThresholdChosenByTheResidual) {
  const sim::SimSession s = norm_session("ln200", 17, 12);
  GravityNormOptions o;
  o.gravity_mps2 = s.gravity_mps2;
  const ThresholdSearch t = detect_and_calibrate_accel(s.samples, {}, o, {2, 4, 8});
  ASSERT_EQ(t.candidates.size(), 3U);
  double best = 1e300;
  for (const auto& c : t.candidates) {
    ASSERT_TRUE(c.fitted);
    best = std::min(best, c.rms_residual_mg);
  }
  EXPECT_DOUBLE_EQ(t.fit.rms_residual_mg, best);
  EXPECT_EQ(t.detection.rule, ThresholdRule::kMultiple);
  EXPECT_DOUBLE_EQ(t.detection.threshold_multiple, t.chosen_multiple);
  EXPECT_NE(t.detection.rule_text.find("smallest |f|-g residual"), std::string::npos);
}

TEST(GravityNorm, Json) {
  const GravityNormResult r = norm_fit(norm_session("ln200", 18, 10));
  const nlohmann::json j = gravity_norm_to_json(r);
  EXPECT_EQ(j["method"], "gravity_norm");
  EXPECT_EQ(j["parameters"].size(), 12U);
  EXPECT_EQ(j["covariance"]["names"].size(), 9U);
  EXPECT_EQ(j["covariance"]["matrix"].size(), 9U);
  EXPECT_EQ(j["poses"].size(), r.poses.size());
  EXPECT_TRUE(j["quality"].contains("rms_residual_mg"));
  EXPECT_TRUE(j["poses"][0].contains("residual_mg"));
  EXPECT_THROW(calibrate_accel_gravity_norm(std::span<const core::ImuSample>(), {}, {}),
               core::InputError);  // no gravity given
}

}  // namespace
}  // namespace calstand::solver
