#include "tablefree/gravity_norm.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <string>

#include "core/error.hpp"
#include "session_truth.hpp"
#include "sim/hand_session.hpp"
#include "sim/spec_sheet.hpp"
#include "tablefree/static_detector.hpp"

namespace calstand::solver {
namespace {

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
      const sim::SimSession s = testing::hand_session_200hz(spec, seed);
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

// The sigmas must be honest where the pose means share a wandering bias (neighbouring poses see
// nearly the same bias, so their residuals are not independent). Over many seeds, the pulls of
// the scale and misalignment parameters (the biases' truth already holds the session's mean
// wander) have an RMS near 1. Measured on these sessions (24 seeds, 144 pulls per class):
// white weights with sigmas scaled by sqrt(chi2/dof) gave flicker 1.16, Gauss-Markov 1.06,
// random walk 1.26, white only 0.93 (at 200 Hz, 20 poses: 1.22, 1.19, 1.28, 0.94); the REML
// noise model with generalised least squares gives 1.12, 0.95, 0.99, 0.94 (1.13, 1.04, 1.02,
// 0.97). The bound 1.2 is what the old scaling fails.
enum class NoiseClass { kWhiteOnly, kAdisFlicker, kLn200GaussMarkov, kRandomWalk };

double wander_rms_pull(NoiseClass kind, int seeds) {
  std::vector<testing::Pull> all;
  for (int seed = 0; seed < seeds; ++seed) {
    sim::HandSessionOptions o;
    o.imu.spec = kind == NoiseClass::kLn200GaussMarkov ? "ln200" : "adis16488";
    o.imu.sample_rate_hz = 100.0;
    o.poses = 24;
    o.initial_rest_s = 20.0;
    if (kind == NoiseClass::kWhiteOnly || kind == NoiseClass::kRandomWalk) {
      sim::ImuTruth t = sim::truth_from_spec(*sim::builtin_spec(o.imu.spec), o.imu.spec,
                                             1000 + static_cast<std::uint64_t>(seed));
      t.accel_noise.bias_instability.setZero();
      t.accel_noise.gauss_markov_sigma.setZero();
      t.accel_noise.random_walk.setZero();
      // An acceleration random walk of 10 ug/sqrt(s): 30 ug between poses 9 s apart, beside the
      // 20 ug white noise of a 5 s pose mean.
      if (kind == NoiseClass::kRandomWalk) t.accel_noise.random_walk.setConstant(1e-4);
      o.imu.truth = t;
    }
    const sim::SimSession s = sim::simulate_hand_session(o, 500 + static_cast<std::uint64_t>(seed));
    const GravityNormResult r = norm_fit(s);
    for (const testing::Pull& p : testing::session_pulls(s, r.parameters)) {
      if (p.name.rfind("accel_bias.", 0) == 0) continue;
      all.push_back(p);
    }
  }
  return testing::rms_pull(all);
}

TEST(GravityNorm, HonestSigmasUnderAWanderingBias) {
  constexpr int kSeeds = 24;
  const double flicker = wander_rms_pull(NoiseClass::kAdisFlicker, kSeeds);
  const double gauss_markov = wander_rms_pull(NoiseClass::kLn200GaussMarkov, kSeeds);
  const double walk = wander_rms_pull(NoiseClass::kRandomWalk, kSeeds);
  const double white = wander_rms_pull(NoiseClass::kWhiteOnly, kSeeds);
  std::printf(
      "RMS pull of scale and misalignment over %d seeds: flicker %.3f, Gauss-Markov %.3f, "
      "random walk %.3f, white only %.3f\n",
      kSeeds, flicker, gauss_markov, walk, white);
  for (double rms : {flicker, gauss_markov, walk, white}) {
    EXPECT_GT(rms, 0.75);
    EXPECT_LT(rms, 1.2);
  }
  // White noise alone: the sigmas are not inflated.
  EXPECT_GT(white, 0.8);
}

// accel_quadratic planted in an LN200-class unit (its other unmodelled terms zeroed).
sim::SimSession quadratic_session(std::uint64_t seed, const Eigen::Vector3d& quadratic) {
  sim::HandSessionOptions o;
  o.imu.spec = "ln200";
  o.imu.sample_rate_hz = 100.0;
  o.poses = 30;
  o.initial_rest_s = 20.0;
  sim::ImuTruth t = sim::truth_from_spec(*sim::builtin_spec("ln200"), "ln200", 2000 + seed);
  t.gyro_g_sensitivity.setZero();
  t.gyro_scale_asymmetry.setZero();
  t.gyro_quadratic.setZero();
  t.accel_scale_asymmetry.setZero();
  t.accel_quadratic = quadratic;
  o.imu.truth = t;
  o.imu.keep_unmodelled_terms = true;
  return sim::simulate_hand_session(o, seed);
}

GravityNormResult quadratic_fit(const sim::SimSession& s, bool fit_quadratic) {
  GravityNormOptions o;
  o.gravity_mps2 = s.gravity_mps2;
  o.fit_quadratic = fit_quadratic;
  return calibrate_accel_gravity_norm(s.samples, detect_static_intervals(s.samples, {}).intervals,
                                      o);
}

TEST(GravityNorm, FitsAccelQuadratic) {
  const Eigen::Vector3d planted(1000.0, -800.0, 600.0);  // ug/g^2
  for (std::uint64_t seed : {31, 32}) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const sim::SimSession s = quadratic_session(seed, planted);
    const GravityNormResult with = quadratic_fit(s, true);
    ASSERT_TRUE(with.quadratic_fitted);
    ASSERT_EQ(with.parameters.size(), 15U);
    ASSERT_EQ(with.covariance.rows(), 12);
    ASSERT_EQ(with.covariance_names.size(), 12U);
    EXPECT_EQ(with.covariance_names[9], "accel_quadratic.x");
    EXPECT_TRUE(with.undetermined.empty());
    int quadratics = 0;
    for (const testing::Pull& p : testing::session_pulls(s, with.parameters)) {
      EXPECT_LT(std::abs(p.pull), 4.0) << p.name;
      if (p.name.rfind("accel_quadratic.", 0) == 0) ++quadratics;
    }
    EXPECT_EQ(quadratics, 3);
    for (int i = 0; i < 3; ++i) {
      const TriadEstimate& e = with.parameters[static_cast<std::size_t>(12 + i)];
      EXPECT_EQ(e.unit, "ug/g^2");
      EXPECT_LT(e.sigma, 250.0) << e.name;  // the planted values are many sigmas
      EXPECT_NEAR(with.quadratic_ug_per_g2[i], planted[i], 4.0 * e.sigma);
    }
    // correct_accel() undoes the forward model, quadratic included.
    const Eigen::Vector3d f(3.0, -5.0, 7.5);
    const Eigen::Vector3d k = with.quadratic_ug_per_g2;
    const double g0 = 9.80665;
    const Eigen::Vector3d measured = with.accel.matrix() * f + with.accel.bias +
                                     1e-6 * g0 * k.cwiseProduct((f / g0).cwiseAbs2());
    EXPECT_LT((correct_accel(with, measured) - f).norm(), 1e-9);
    // Without the term the poses do not fit.
    const GravityNormResult without = quadratic_fit(s, false);
    EXPECT_GT(without.chi2_per_dof, 4.0 * std::max(1.0, with.chi2_per_dof))
        << without.chi2_per_dof << " vs " << with.chi2_per_dof;
    EXPECT_GT(without.rms_residual_mg, 2.0 * with.rms_residual_mg);
  }
  // Fitted on a session without it: consistent with zero.
  for (std::uint64_t seed : {33, 34}) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const GravityNormResult r =
        quadratic_fit(quadratic_session(seed, Eigen::Vector3d::Zero()), true);
    for (int i = 0; i < 3; ++i) {
      const TriadEstimate& e = r.parameters[static_cast<std::size_t>(12 + i)];
      ASSERT_GT(e.sigma, 0.0);
      EXPECT_LT(std::abs(e.value / e.sigma), 3.5) << e.name << " " << e.value << " +- " << e.sigma;
    }
  }
}

TEST(GravityNorm, ConventionFixesTheUpperMisalignments) {
  const GravityNormResult r = norm_fit(testing::hand_session_200hz("ln200", 14));
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
  const sim::SimSession s =
      testing::hand_session_200hz("adis16488", 15, 7);  // the rest and 7 poses
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
  // With the quadratic: the y axis never feels gravity, so accel_quadratic.y is not determined
  // either; x and z are.
  GravityNormOptions q;
  q.gravity_mps2 = s.gravity_mps2;
  q.fit_quadratic = true;
  const GravityNormResult rq =
      calibrate_accel_gravity_norm(s.samples, detect_static_intervals(s.samples, {}).intervals, q);
  std::vector<std::string> uq = rq.undetermined;
  std::sort(uq.begin(), uq.end());
  EXPECT_EQ(uq, (std::vector<std::string>{"accel_bias.y", "accel_misalignment.yx",
                                          "accel_misalignment.zy", "accel_quadratic.y",
                                          "accel_scale.y"}));
}

TEST(GravityNorm, ThresholdChosenByTheResidual) {
  const sim::SimSession s = testing::hand_session_200hz("ln200", 17, 12);
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
  const GravityNormResult r = norm_fit(testing::hand_session_200hz("ln200", 18, 10));
  const nlohmann::json j = gravity_norm_to_json(r);
  EXPECT_EQ(j["method"], "gravity_norm");
  EXPECT_EQ(j["parameters"].size(), 12U);
  EXPECT_EQ(j["covariance"]["names"].size(), 9U);
  EXPECT_EQ(j["covariance"]["matrix"].size(), 9U);
  EXPECT_EQ(j["poses"].size(), r.poses.size());
  EXPECT_TRUE(j["quality"].contains("rms_residual_mg"));
  EXPECT_TRUE(j["poses"][0].contains("residual_mg"));
  EXPECT_TRUE(j["noise_model"].contains("description"));
  EXPECT_EQ(j["noise_model"]["residuals"], r.poses.size());
  EXPECT_THROW(calibrate_accel_gravity_norm(std::span<const core::ImuSample>(), {}, {}),
               core::InputError);  // no gravity given
}

}  // namespace
}  // namespace calstand::solver
