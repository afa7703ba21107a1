// The noise JSON and the one "long enough static record" threshold, on static records of the
// known IMU (white noise of known density only).
#include "analysis/noise_json.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "recorded_run.hpp"

namespace calstand::analysis {
namespace {

// The known IMU's angle random walk [deg/sqrt(h)] (tests/integration/known_imu_station.hpp).
constexpr double kTrueArwDegRtH = 0.1;

std::int64_t static_run(const std::string& db, int duration_s) {
  return testing::record_run(db, "static-allan",
                             {"duration_s=" + std::to_string(duration_s), "soak_s=1", "warmup_s=1"},
                             21);
}

TEST(NoiseRecordThreshold, IsOneConstantWithASamplePeriodsSlack) {
  EXPECT_TRUE(long_enough_for_noise(kMinNoiseRecordS));
  EXPECT_TRUE(long_enough_for_noise(kMinNoiseRecordS - 0.005));  // 600 s at 200 Hz, first to last
  EXPECT_FALSE(long_enough_for_noise(0.9 * kMinNoiseRecordS));
  EXPECT_FALSE(long_enough_for_noise(100.0));  // what `calibrate` used to take
}

TEST(CalibrationNoiseFigures, ALongStaticRecordGivesTheTrueRandomWalk) {
  testing::TempDatabase file("noise-long");
  const std::int64_t run = static_run(file.path(), static_cast<int>(kMinNoiseRecordS));
  store::Database db(file.path());
  const nlohmann::json j = calibration_noise_figures(db, run, "imu0");
  ASSERT_TRUE(j.is_object()) << j;
  EXPECT_EQ(j.at("step"), 3);
  EXPECT_GE(j.at("duration_s").get<double>(), 0.99 * kMinNoiseRecordS);
  for (const char* channel : {"gx", "gy", "gz"}) {
    bool found = false;
    for (const auto& f : j.at("channels").at(channel)) {
      if (f.at("name") != "angle_random_walk") continue;
      found = true;
      EXPECT_EQ(f.at("unit"), "deg/sqrt(h)");
      EXPECT_NEAR(f.at("value").get<double>(), kTrueArwDegRtH, 0.15 * kTrueArwDegRtH) << channel;
    }
    EXPECT_TRUE(found) << channel;
  }
  // What the exports read back (calibration_noise_terms): the rate, and the white noise in the
  // data's unit again.
  EXPECT_NEAR(j.at("sample_rate_hz").get<double>(), 200.0, 1e-6);
  const auto terms = calibration_noise_terms(j);
  ASSERT_TRUE(terms.has_value());
  EXPECT_NEAR(terms->sample_rate_hz, 200.0, 1e-6);
  ASSERT_EQ(terms->channels.size(), 6u);
  EXPECT_NEAR(terms->channels[0].terms.random_walk.value, kTrueArwDegRtH / 60.0,
              0.15 * kTrueArwDegRtH / 60.0);

  // Beside them, each channel's identified model's figures (the Kalibr export's): on this white
  // record the GMWM's white density, N in deg/s/sqrt(Hz), with an interval holding the truth.
  const auto models = calibration_noise_models(j);
  ASSERT_TRUE(models.has_value()) << j.dump();
  ASSERT_EQ(models->size(), 6u);
  for (std::size_t i = 0; i < 3; ++i) {
    const auto& figures = (*models)[i].figures;
    const auto n = std::find_if(figures.begin(), figures.end(), [](const solver::ModelFigure& f) {
      return f.name == "white_density";
    });
    ASSERT_NE(n, figures.end()) << i;
    EXPECT_EQ(n->estimator, "gmwm") << i;
    EXPECT_EQ(n->unit, "deg/s/sqrt(Hz)") << i;
    EXPECT_NEAR(n->value, kTrueArwDegRtH / 60.0, 0.05 * kTrueArwDegRtH / 60.0) << i;
    EXPECT_LT(n->lo, kTrueArwDegRtH / 60.0) << i;
    EXPECT_GT(n->hi, kTrueArwDegRtH / 60.0) << i;
  }
  nlohmann::json old_record = j;
  old_record.erase("model_figures");
  EXPECT_FALSE(calibration_noise_models(old_record).has_value());
}

TEST(CalibrationNoiseTerms, ReadTheFiguresBackInTheDataUnit) {
  // Figures as calibration_noise_figures writes them, in datasheet units.
  nlohmann::json channels;
  for (const char* g : {"gx", "gy", "gz"}) {
    channels[g] = {{{"name", "angle_random_walk"},
                    {"value", 0.3},
                    {"unit", "deg/sqrt(h)"},
                    {"resolved", true}},
                   {{"name", "rate_random_walk"},
                    {"value", 2.16},
                    {"unit", "deg/h/sqrt(h)"},
                    {"resolved", false}}};
  }
  for (const char* a : {"ax", "ay", "az"}) {
    channels[a] = {{{"name", "velocity_random_walk"},
                    {"value", 0.06},
                    {"unit", "m/s/sqrt(h)"},
                    {"resolved", true}},
                   {{"name", "acceleration_random_walk"},
                    {"value", 0.432},
                    {"unit", "m/s/h/sqrt(h)"},
                    {"resolved", true}}};
  }
  const nlohmann::json noise = {{"step", 2}, {"sample_rate_hz", 125.0}, {"channels", channels}};
  const auto terms = calibration_noise_terms(noise);
  ASSERT_TRUE(terms.has_value());
  EXPECT_EQ(terms->sample_rate_hz, 125.0);
  ASSERT_EQ(terms->channels.size(), 6u);
  const auto& gz = terms->channels[2];
  EXPECT_EQ(gz.channel, solver::ImuChannel::kGz);
  EXPECT_NEAR(gz.terms.random_walk.value, 0.3 / 60.0, 1e-15);            // deg/sqrt(s)
  EXPECT_NEAR(gz.terms.rate_random_walk.value, 2.16 / 216000.0, 1e-18);  // deg/s/sqrt(s)
  EXPECT_TRUE(gz.terms.random_walk.resolved);
  EXPECT_FALSE(gz.terms.rate_random_walk.resolved);
  const auto& ay = terms->channels[4];
  EXPECT_NEAR(ay.terms.random_walk.value, 0.06 / 60.0, 1e-15);
  EXPECT_NEAR(ay.terms.rate_random_walk.value, 0.432 / 216000.0, 1e-18);

  EXPECT_FALSE(calibration_noise_terms(nullptr).has_value());
  nlohmann::json broken = noise;
  broken["channels"]["ay"][1]["unit"] = "m/s";  // not a random walk's dimension
  try {
    calibration_noise_terms(broken);
    ADD_FAILURE() << "accepted";
  } catch (const core::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("ay"), std::string::npos) << e.what();
  }
}

TEST(CalibrationNoiseFigures, AShortStaticRecordGivesNone) {
  testing::TempDatabase file("noise-short");
  const std::int64_t run = static_run(file.path(), 300);
  store::Database db(file.path());
  EXPECT_TRUE(calibration_noise_figures(db, run, "imu0").is_null());
}

TEST(RunNoiseJson, HoldsEveryChannelWithFiguresAndTermsInTheDataUnit) {
  testing::TempDatabase file("noise-json");
  const std::int64_t run = static_run(file.path(), 300);
  store::Database db(file.path());
  solver::RunNoiseOptions options;
  const solver::RunNoise noise = solver::analyse_run_noise(db, run, options);
  const nlohmann::ordered_json j = run_noise_json(noise);
  EXPECT_EQ(j.at("run"), run);
  EXPECT_EQ(j.at("device"), "imu0");
  EXPECT_NEAR(j.at("sample_rate_hz").get<double>(), 200.0, 1e-6);
  ASSERT_EQ(j.at("channels").size(), 6u);
  const auto& gx = j.at("channels").at(0);
  EXPECT_EQ(gx.at("channel"), "gx");
  EXPECT_EQ(gx.at("unit"), "deg/s");
  const auto& rw = gx.at("terms").at("random_walk");
  EXPECT_EQ(rw.at("unit"), "deg/s/sqrt(Hz)");
  // deg/sqrt(h) to deg/s/sqrt(Hz): divide by 60.
  EXPECT_NEAR(rw.at("value").get<double>(), kTrueArwDegRtH / 60.0, 0.15 * kTrueArwDegRtH / 60.0);
  EXPECT_TRUE(gx.at("figures").is_array());
  // The keys keep the documented order (ordered_json).
  EXPECT_EQ(j.begin().key(), "run");
}

TEST(AllanJson, ListsTheCurveAndNullNoiseWithoutAFit) {
  solver::AllanResult r;
  r.samples = 1000;
  r.confidence = 0.683;
  r.points.push_back({});
  r.points.back().tau_s = 1.0;
  r.points.back().deviation = 0.5;
  const nlohmann::ordered_json j =
      allan_json(r, "test", "adev", "deg/s", 100.0, std::nullopt, std::nullopt);
  EXPECT_EQ(j.at("kind"), "adev");
  EXPECT_EQ(j.at("tau").at(0), 1.0);
  EXPECT_EQ(j.at("adev").at(0), 0.5);
  EXPECT_TRUE(j.contains("adev_lo"));
  EXPECT_TRUE(j.at("noise").is_null());
}

}  // namespace
}  // namespace calstand::analysis
