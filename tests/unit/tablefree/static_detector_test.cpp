#include "tablefree/static_detector.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "core/error.hpp"
#include "session_truth.hpp"
#include "sim/hand_session.hpp"

namespace calstand::solver {
namespace {

// Every simulated hold is found once, inside the hold and at most a window (plus a sample)
// short of each end; nothing else is found.
void expect_holds_found(const sim::SimSession& s, const StaticDetection& d) {
  ASSERT_EQ(d.intervals.size(), s.holds.size());
  const double slack = d.window_s + 2.0 / s.sample_rate_hz;
  for (std::size_t k = 0; k < s.holds.size(); ++k) {
    const sim::SessionHold& h = s.holds[k];
    const StaticInterval& in = d.intervals[k];
    SCOPED_TRACE("hold " + std::to_string(k));
    EXPECT_GE(in.start_s, h.start_s - 0.05);
    EXPECT_LE(in.start_s, h.start_s + slack);
    EXPECT_LE(in.end_s, h.end_s + 0.05);
    EXPECT_GE(in.end_s, h.end_s - slack);
    EXPECT_EQ(in.initial_rest, k == 0);
  }
}

TEST(StaticDetector, FindsTheSimulatedHoldsAndTheRest) {
  for (const char* spec : {"adis16488", "ln200"}) {
    for (std::uint64_t seed : {3, 4}) {
      SCOPED_TRACE(std::string(spec) + " seed " + std::to_string(seed));
      const sim::SimSession s = testing::hand_session_200hz(spec, seed);
      const StaticDetection d = detect_static_intervals(s.samples, {});
      expect_holds_found(s, d);
      EXPECT_TRUE(d.has_initial_rest);
      EXPECT_TRUE(d.rest_from_data);
      EXPECT_NEAR(d.rest_end_s, s.holds[0].end_s, d.window_s);
      EXPECT_EQ(d.rule, ThresholdRule::kRestQuantile);
      EXPECT_GE(d.threshold_multiple, 3.0);
      EXPECT_NEAR(d.threshold_mps2_sq, d.threshold_multiple * d.rest_level_mps2_sq, 1e-15);
      EXPECT_NE(d.rule_text.find("effective degrees of freedom"), std::string::npos);
    }
  }
}

TEST(StaticDetector, OptionsOverrideEveryChoice) {
  const sim::SimSession s = testing::hand_session_200hz("adis16488", 5, 12);
  StaticDetectorOptions o;
  o.initial_rest_s = 20.0;
  o.rule = ThresholdRule::kMultiple;
  o.threshold_multiple = 8.0;
  const StaticDetection d = detect_static_intervals(s.samples, o);
  EXPECT_FALSE(d.rest_from_data);
  EXPECT_NEAR(d.rest_end_s, s.samples.front().receive_time_s + 20.0, 1e-9);
  EXPECT_DOUBLE_EQ(d.threshold_multiple, 8.0);
  expect_holds_found(s, d);

  o.rule = ThresholdRule::kAbsolute;
  o.absolute_threshold = 3.0 * d.rest_level_mps2_sq;
  const StaticDetection a = detect_static_intervals(s.samples, o);
  EXPECT_DOUBLE_EQ(a.threshold_mps2_sq, o.absolute_threshold);
  EXPECT_NEAR(a.threshold_multiple, 3.0, 1e-9);

  // A minimum duration longer than every hold leaves only the rest.
  o.min_duration_s = 15.0;
  const StaticDetection r = detect_static_intervals(s.samples, o);
  ASSERT_EQ(r.intervals.size(), 1U);
  EXPECT_TRUE(r.intervals[0].initial_rest);
  EXPECT_EQ(r.rejected_short, s.holds.size() - 1);
}

TEST(StaticDetector, RefusesWhatItCannotUse) {
  const sim::SimSession s = testing::hand_session_200hz("ln200", 6, 10);
  // Starting in the middle of a turn: no quiet start.
  const std::size_t turn = s.turns[0].begin + 20;
  const std::span<const core::ImuSample> moving(s.samples.data() + turn, s.samples.size() - turn);
  try {
    detect_static_intervals(moving, {});
    FAIL() << "a recording that does not start at rest was accepted";
  } catch (const core::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("does not start at rest"), std::string::npos) << e.what();
  }
  std::vector<core::ImuSample> bad(s.samples.begin(), s.samples.begin() + 2000);
  bad[100].receive_time_s = bad[99].receive_time_s;
  EXPECT_THROW(detect_static_intervals(bad, {}), core::InputError);
  StaticDetectorOptions o;
  o.window_s = -1.0;
  EXPECT_THROW(detect_static_intervals(s.samples, o), core::InputError);
}

TEST(StaticDetector, JsonForShow) {
  const sim::SimSession s = testing::hand_session_200hz("ln200", 7, 10);
  const nlohmann::json j = static_detection_to_json(detect_static_intervals(s.samples, {}));
  EXPECT_EQ(j["rule"], "rest_quantile");
  ASSERT_EQ(j["intervals"].size(), s.holds.size());
  const auto& first = j["intervals"][0];
  EXPECT_TRUE(first["initial_rest"].get<bool>());
  for (const char* key : {"begin", "end", "start_s", "end_s", "duration_s", "mean_accel_mps2",
                          "mean_gyro_dps", "statistic_mps2_sq"}) {
    EXPECT_TRUE(first.contains(key)) << key;
  }
  EXPECT_TRUE(j["rest"].contains("effective_dof"));
}

}  // namespace
}  // namespace calstand::solver
