// The figures users read from the identified model or the Allan line (noise/model_figures.hpp)
// and the Kalibr figures chosen from them: which estimator gives each figure, and why.
#include "noise/model_figures.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "noise/kalibr.hpp"

namespace calstand::solver {
namespace {

const ModelFigure* find(const std::vector<ModelFigure>& figures, const std::string& name) {
  for (const auto& f : figures) {
    if (f.name == name) return &f;
  }
  return nullptr;
}

NoiseTerms allan_terms(double n, double b, double k) {
  NoiseTerms t;
  t.random_walk = {n, 0.1 * n, true};
  t.bias_instability = {b, 0.2 * b, b > 0.0};
  t.rate_random_walk = {k, 0.3 * k, k > 0.0};
  return t;
}

NoiseModelTerm term(NoiseKind kind, double value, double tau_s = 0.0) {
  NoiseModelTerm t;
  t.kind = kind;
  t.value = value;
  t.value_lo = 0.9 * value;
  t.value_hi = 1.1 * value;
  t.tau_s = tau_s;
  t.tau_lo_s = 0.8 * tau_s;
  t.tau_hi_s = 1.25 * tau_s;
  return t;
}

TEST(ModelFigures, TheModelsTermsWhereSelectedTheAllanLineElsewhere) {
  NoiseModel model;
  // Two Gauss-Markov terms given longest first: the figures list them by correlation time.
  model.terms = {term(NoiseKind::kWhite, 0.005), term(NoiseKind::kGaussMarkov, 0.003, 100.0),
                 term(NoiseKind::kGaussMarkov, 0.004, 0.5)};
  const auto figures = model_figures(model, allan_terms(0.0051, 0.002, 4e-4), "deg/s", "");
  const ModelFigure* white = find(figures, "white_density");
  ASSERT_NE(white, nullptr);
  EXPECT_EQ(white->estimator, "gmwm");
  EXPECT_EQ(white->value, 0.005);
  EXPECT_EQ(white->lo, 0.9 * 0.005);
  EXPECT_EQ(white->unit, "deg/s/sqrt(Hz)");
  // No flicker and no random walk selected: the Allan line's, with +- 1.96 sigma and why.
  const ModelFigure* b = find(figures, "bias_instability");
  ASSERT_NE(b, nullptr);
  EXPECT_EQ(b->estimator, "allan-line");
  EXPECT_EQ(b->value, 0.002);
  EXPECT_NEAR(b->hi, 0.002 + 1.96 * 0.0004, 1e-6);
  EXPECT_NE(b->note.find("no flicker term"), std::string::npos) << b->note;
  const ModelFigure* k = find(figures, "random_walk");
  ASSERT_NE(k, nullptr);
  EXPECT_EQ(k->estimator, "allan-line");
  EXPECT_EQ(k->unit, "deg/s/sqrt(s)");
  std::vector<double> taus;
  for (const auto& f : figures) {
    if (f.name == "gauss_markov_tau") {
      EXPECT_EQ(f.estimator, "gmwm");
      EXPECT_EQ(f.unit, "s");
      taus.push_back(f.value);
    }
  }
  EXPECT_EQ(taus, (std::vector<double>{0.5, 100.0}));
}

TEST(ModelFigures, WithoutAModelEveryFigureIsTheAllanLinesWithTheReason) {
  const auto figures =
      model_figures(std::nullopt, allan_terms(0.01, 0.0, 0.0), "m/s^2", "the record lasts 300 s");
  ASSERT_EQ(figures.size(), 3u);  // white density, bias instability, random walk
  for (const auto& f : figures) {
    EXPECT_EQ(f.estimator, "allan-line") << f.name;
    EXPECT_EQ(f.note, "the record lasts 300 s") << f.name;
  }
  EXPECT_FALSE(find(figures, "random_walk")->resolved);  // the Allan line put it at zero
  EXPECT_TRUE(find(figures, "white_density")->resolved);
}

TEST(ModelFigures, AShortRecordIsNotIdentified) {
  RunNoise noise;
  noise.duration_s = 300.0;
  noise.sample_rate_hz = 100.0;
  for (ImuChannel c : kAllChannels) {
    ChannelNoise ch;
    ch.channel = c;
    ch.terms = allan_terms(0.01, 0.001, 1e-4);
    noise.channels.push_back(ch);
  }
  // No samples are needed: the record's length alone rules the model out.
  const auto models = channel_noise_models(std::span<const core::ImuSample>(), noise);
  ASSERT_EQ(models.size(), 6u);
  for (const auto& m : models) {
    EXPECT_FALSE(m.model.has_value());
    EXPECT_NE(m.note.find("the record lasts 300 s"), std::string::npos) << m.note;
    EXPECT_EQ(find(m.figures, "white_density")->estimator, "allan-line");
  }
}

TEST(ModelFigures, KalibrTakesTheModelOnlyWhereEveryAxisHasIt) {
  RunNoise noise;
  noise.sample_rate_hz = 200.0;
  std::vector<ChannelModelFigures> models;
  for (ImuChannel c : kAllChannels) {
    ChannelNoise ch;
    ch.channel = c;
    ch.terms = allan_terms(is_gyro(c) ? 0.006 : 0.0006, 0.001, is_gyro(c) ? 5e-4 : 5e-5);
    noise.channels.push_back(ch);
    NoiseModel model;
    const double n = (is_gyro(c) ? 0.005 : 0.0005) * (1.0 + 0.1 * static_cast<int>(c));
    model.terms = {term(NoiseKind::kWhite, n)};
    // A random walk on every gyro axis, on two accelerometer axes only.
    if (is_gyro(c) || c != ImuChannel::kAz) {
      model.terms.push_back(term(NoiseKind::kRandomWalk, is_gyro(c) ? 4e-4 : 4e-5));
    }
    ChannelModelFigures m;
    m.channel = c;
    m.model = model;
    m.figures = model_figures(m.model, ch.terms, std::string(channel_unit(c)), "");
    models.push_back(m);
  }
  std::vector<std::string> unresolved;
  const KalibrImu imu = kalibr_from_noise_models(noise, models, "/imu0", &unresolved);
  constexpr double kRad = std::numbers::pi / 180.0;
  EXPECT_EQ(imu.gyroscope_noise_density_estimator, "gmwm");
  EXPECT_NEAR(imu.gyroscope_noise_density, 0.005 * 1.2 * kRad, 1e-15);  // the worst axis, gz
  EXPECT_EQ(imu.gyroscope_random_walk_estimator, "gmwm");
  EXPECT_NEAR(imu.gyroscope_random_walk, 4e-4 * kRad, 1e-15);
  EXPECT_EQ(imu.accelerometer_noise_density_estimator, "gmwm");
  EXPECT_NEAR(imu.accelerometer_noise_density, 0.0005 * 1.5, 1e-15);
  // az has no random walk in its model: the whole field is the Allan line's (one number, one
  // estimator), as kalibr_from_run_noise() gives it.
  EXPECT_EQ(imu.accelerometer_random_walk_estimator, "allan-line");
  EXPECT_EQ(imu.accelerometer_random_walk, kalibr_from_run_noise(noise).accelerometer_random_walk);
  EXPECT_TRUE(unresolved.empty());
  const std::string yaml = kalibr_yaml(imu);
  EXPECT_NE(yaml.find("# [m/s^3/sqrt(Hz)] estimator: allan-line"), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("# [rad/s^2/sqrt(Hz)] estimator: gmwm"), std::string::npos) << yaml;
}

}  // namespace
}  // namespace calstand::solver
