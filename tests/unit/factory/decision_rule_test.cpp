// The guard-band decision rule at its boundaries: pass when value +- k sigma is inside the
// limit (limits included), fail when it is wholly outside, indeterminate in between; k widens
// the band; a unit takes its worst check.
#include "factory/decision_rule.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace calstand::analysis {
namespace {

const Bounds kAbs{0.005, std::nullopt, std::nullopt};  // |v| <= 0.005

Verdict rule_verdict(double value, double sigma, const Bounds& b, double k = 2.0) {
  return judge(value, sigma, b, k).verdict;
}

TEST(DecisionRule, MaxAbsBoundariesWithTheGuardBand) {
  // sigma 0.001, k 2: w = 0.002. Values chosen exactly representable around the edges.
  const double s = 0.001;
  EXPECT_EQ(rule_verdict(0.0, s, kAbs), Verdict::kPass);
  EXPECT_EQ(rule_verdict(0.0029, s, kAbs), Verdict::kPass);           // 0.0049 inside
  EXPECT_EQ(rule_verdict(-0.0029, s, kAbs), Verdict::kPass);          // both signs
  EXPECT_EQ(rule_verdict(0.0031, s, kAbs), Verdict::kIndeterminate);  // 0.0051 crosses the limit
  EXPECT_EQ(rule_verdict(0.005, s, kAbs), Verdict::kIndeterminate);   // on the limit
  EXPECT_EQ(rule_verdict(0.0069, s, kAbs), Verdict::kIndeterminate);  // 0.0049 still inside
  EXPECT_EQ(rule_verdict(0.0071, s, kAbs), Verdict::kFail);           // 0.0051 wholly outside
  EXPECT_EQ(rule_verdict(-0.0071, s, kAbs), Verdict::kFail);
}

TEST(DecisionRule, LimitsBelongToTheZone) {
  // Without a guard band a value on the limit conforms; just beyond it does not.
  EXPECT_EQ(rule_verdict(0.005, 0.0, kAbs), Verdict::kPass);
  EXPECT_EQ(rule_verdict(-0.005, 0.0, kAbs), Verdict::kPass);
  EXPECT_EQ(rule_verdict(0.00500001, 0.0, kAbs), Verdict::kFail);
  // With one: value + w exactly on the limit passes, value - w exactly on it is not a fail.
  const Bounds max4{std::nullopt, std::nullopt, 4.0};
  EXPECT_EQ(rule_verdict(3.0, 0.5, max4), Verdict::kPass);           // 3 + 1 = 4
  EXPECT_EQ(rule_verdict(5.0, 0.5, max4), Verdict::kIndeterminate);  // 5 - 1 = 4
  EXPECT_EQ(rule_verdict(5.25, 0.5, max4), Verdict::kFail);          // 4.25 > 4
}

TEST(DecisionRule, KWidensTheBand) {
  const double s = 0.001;
  EXPECT_EQ(rule_verdict(0.0035, s, kAbs, 1.0), Verdict::kPass);  // 0.0045
  EXPECT_EQ(rule_verdict(0.0035, s, kAbs, 2.0), Verdict::kIndeterminate);
  EXPECT_EQ(rule_verdict(0.0065, s, kAbs, 1.0), Verdict::kFail);  // 0.0055 outside
  EXPECT_EQ(rule_verdict(0.0065, s, kAbs, 2.0), Verdict::kIndeterminate);
  // k = 0 is simple acceptance without a band: never indeterminate.
  EXPECT_EQ(rule_verdict(0.00499, 1.0, kAbs, 0.0), Verdict::kPass);
  EXPECT_EQ(rule_verdict(0.00501, 1.0, kAbs, 0.0), Verdict::kFail);
}

TEST(DecisionRule, TwoSidedZones) {
  const Bounds zone{std::nullopt, 1.0, 2.0};
  EXPECT_EQ(rule_verdict(1.5, 0.1, zone), Verdict::kPass);
  EXPECT_EQ(rule_verdict(1.1, 0.1, zone), Verdict::kIndeterminate);  // 0.9 below min
  EXPECT_EQ(rule_verdict(1.9, 0.1, zone), Verdict::kIndeterminate);  // 2.1 above max
  EXPECT_EQ(rule_verdict(0.7, 0.1, zone), Verdict::kFail);           // [0.5, 0.9] below
  EXPECT_EQ(rule_verdict(2.3, 0.1, zone), Verdict::kFail);           // [2.1, 2.5] above
  // An interval wider than the zone straddles both limits: indeterminate, not pass.
  EXPECT_EQ(rule_verdict(1.5, 1.0, zone), Verdict::kIndeterminate);
  const Bounds at_least{std::nullopt, 10.0, std::nullopt};
  EXPECT_EQ(rule_verdict(12.0, 1.0, at_least), Verdict::kPass);
  EXPECT_EQ(rule_verdict(11.0, 1.0, at_least), Verdict::kIndeterminate);
  EXPECT_EQ(rule_verdict(7.5, 1.0, at_least), Verdict::kFail);
}

TEST(DecisionRule, NotANumberFails) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(rule_verdict(nan, 0.0, kAbs), Verdict::kFail);
  EXPECT_EQ(rule_verdict(0.0, nan, kAbs), Verdict::kFail);
  EXPECT_EQ(rule_verdict(0.0, -1.0, kAbs), Verdict::kFail);
  EXPECT_EQ(rule_verdict(0.0, 0.0, Bounds{}), Verdict::kFail);  // nothing to judge against
}

TEST(DecisionRule, TheReasonShowsTheEdgeThatDecided) {
  const Judgement fail = judge(0.0071, 0.001, kAbs, 2.0);
  EXPECT_NE(fail.reason.find("|v| - 2 sigma = 0.0051 > 0.005"), std::string::npos) << fail.reason;
  const Judgement pass = judge(0.5, 0.0, Bounds{std::nullopt, std::nullopt, 2.0}, 2.0);
  EXPECT_EQ(pass.reason, "v = 0.5 <= 2");  // no band to speak of
}

TEST(DecisionRule, AUnitTakesItsWorstCheck) {
  using V = Verdict;
  EXPECT_EQ(combine({V::kPass, V::kPass}), V::kPass);
  EXPECT_EQ(combine({V::kPass, V::kIndeterminate, V::kPass}), V::kIndeterminate);
  EXPECT_EQ(combine({V::kIndeterminate, V::kFail, V::kPass}), V::kFail);
  EXPECT_EQ(combine({}), V::kIndeterminate);  // nothing shown: no pass
  EXPECT_EQ(to_string(V::kIndeterminate), "indeterminate");
}

TEST(DecisionRule, BoundsInWordsAndJson) {
  EXPECT_EQ(describe(kAbs, "deg/s"), "|v| <= 0.005 deg/s");
  EXPECT_EQ(describe(Bounds{std::nullopt, -1.0, 1.0}, ""), "-1 <= v <= 1");
  EXPECT_EQ(limit_json(Bounds{std::nullopt, 1.0, std::nullopt}), 1.0);
  EXPECT_EQ(limit_kind(Bounds{std::nullopt, 1.0, std::nullopt}), "min");
  EXPECT_EQ(limit_json(Bounds{std::nullopt, -1.0, 1.0}), nlohmann::json::array({-1.0, 1.0}));
  EXPECT_EQ(limit_kind(Bounds{std::nullopt, -1.0, 1.0}), "min_max");
  EXPECT_EQ(limit_json(kAbs), 0.005);
  EXPECT_NE(decision_rule_text(2.0).find("k = 2"), std::string::npos);
}

}  // namespace
}  // namespace calstand::analysis
