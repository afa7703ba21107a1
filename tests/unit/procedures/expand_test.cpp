// Expansion: nested loops, references, labels, the rest rule of rate steps, and the value rules
// (one bad procedure per rule, exact path and message).
#include <gtest/gtest.h>

#include "procedures/procedure.hpp"
#include "test_util.hpp"

namespace calstand::procedures {
namespace {

using nlohmann::json;
using test::doc_with;
using test::expand_violations;
using test::parse;

TEST(Expand, NestedLoopsUnrollInOrderWithOriginAndLoopValues) {
  const Procedure p = parse(doc_with(R"([
    {"kind": "move", "outer_deg": 0, "inner_deg": 0},
    {"kind": "for_each", "var": "t", "values": "${temps}", "steps": [
      {"kind": "set_temperature", "target_c": "${t}"},
      {"kind": "for_each", "var": "side", "values": ["up", "down"], "steps": [
        {"kind": "capture", "duration_s": 10, "label": "${side} at ${t} degC"}]}]}])",
                                     R"({"temps": {"default": [-40, 25.5], "description": "d"}})"));
  const auto steps = expand(p);
  ASSERT_EQ(steps.size(), 7u);
  const char* labels[] = {
      "move to outer 0, inner 0", "temperature ramp to -40 degC",  "up at -40 degC",
      "down at -40 degC",         "temperature ramp to 25.5 degC", "up at 25.5 degC",
      "down at 25.5 degC"};
  for (std::size_t i = 0; i < steps.size(); ++i) {
    EXPECT_EQ(steps[i].index, i);
    EXPECT_EQ(steps[i].label, labels[i]);
  }
  EXPECT_EQ(steps[0].origin_path, "steps[0]");
  EXPECT_TRUE(steps[0].loop_values.empty());
  EXPECT_EQ(steps[4].kind, StepKind::kSetTemperature);
  EXPECT_EQ(steps[4].origin_path, "steps[1].steps[0]");
  EXPECT_DOUBLE_EQ(steps[4].target_c, 25.5);
  EXPECT_EQ(steps[4].references.at("target_c"), "${t}");
  EXPECT_EQ(steps[6].origin_path, "steps[1].steps[1].steps[0]");
  const std::vector<std::pair<std::string, json>> loops{{"t", 25.5}, {"side", "down"}};
  EXPECT_EQ(steps[6].loop_values, loops);
}

TEST(Expand, NegatedReferenceAndRevolutions) {
  const auto steps = expand(parse(doc_with(
      R"([{"kind": "for_each", "var": "r", "values": [30], "steps": [
            {"kind": "rate", "axis": "inner", "rate_dps": "-${r}", "revolutions": 3}]}])")));
  ASSERT_EQ(steps.size(), 1u);
  EXPECT_DOUBLE_EQ(steps[0].rate_dps, -30.0);
  EXPECT_DOUBLE_EQ(*steps[0].revolutions, 3.0);
  EXPECT_DOUBLE_EQ(steps[0].duration_s, 36.0);  // 3 * 360 deg / 30 deg/s
  EXPECT_DOUBLE_EQ(steps[0].settle_s, 2.0);     // default
  EXPECT_EQ(steps[0].label, "inner rate -30 deg/s");
}

TEST(Expand, RateStepsRestUnlessTheNextIsARateOnTheSameAxis) {
  const auto steps = expand(parse(doc_with(R"([
    {"kind": "rate", "axis": "outer", "rate_dps": 10, "duration_s": 1},
    {"kind": "rate", "axis": "outer", "rate_dps": -10, "duration_s": 1},
    {"kind": "rate", "axis": "inner", "rate_dps": 10, "duration_s": 1},
    {"kind": "capture", "duration_s": 1, "label": "after"},
    {"kind": "rate", "axis": "inner", "rate_dps": 10, "duration_s": 1}])")));
  ASSERT_EQ(steps.size(), 5u);
  EXPECT_FALSE(steps[0].rest_after);
  EXPECT_TRUE(steps[1].rest_after);  // next is on the other axis
  EXPECT_TRUE(steps[2].rest_after);  // next is a capture
  EXPECT_TRUE(steps[4].rest_after);  // last step
}

TEST(Expand, SetTemperatureWithAndWithoutSoak) {
  const auto steps = expand(parse(doc_with(R"([
    {"kind": "set_temperature", "target_c": 85, "ramp_c_per_min": 2,
     "soak": {"tolerance_c": 0.5, "stable_s": 600, "timeout_s": 3600}},
    {"kind": "set_temperature", "target_c": -40}])")));
  ASSERT_EQ(steps.size(), 2u);
  EXPECT_TRUE(steps[0].wait_for_soak);
  EXPECT_DOUBLE_EQ(*steps[0].ramp_c_per_min, 2.0);
  EXPECT_DOUBLE_EQ(steps[0].soak.stable_s, 600.0);
  EXPECT_DOUBLE_EQ(steps[0].soak.timeout_s, 3600.0);
  EXPECT_EQ(steps[0].label, "temperature 85 degC");
  EXPECT_FALSE(steps[1].wait_for_soak);
  EXPECT_FALSE(steps[1].ramp_c_per_min.has_value());
  EXPECT_EQ(steps[0].to_json()["soak"]["stable_s"], 600.0);
  EXPECT_FALSE(steps[1].to_json().contains("soak"));
}

// --- Value rules -------------------------------------------------------------------------------

TEST(ValueRules, DurationMustBePositive) {
  EXPECT_ONE_VIOLATION(expand_violations(parse(doc_with(R"([{"kind": "wait", "duration_s": 0}])"))),
                       "steps[0].duration_s", "0 must be greater than 0");
}

TEST(ValueRules, ReferencedDurationNamesTheReference) {
  EXPECT_ONE_VIOLATION(expand_violations(parse(
                           doc_with(R"([{"kind": "capture", "duration_s": "${d}", "label": "a"}])",
                                    R"({"d": {"default": -5, "description": "d"}})"))),
                       "steps[0].duration_s", "${d} = -5 must be greater than 0");
}

TEST(ValueRules, RampMustBePositive) {
  EXPECT_ONE_VIOLATION(
      expand_violations(
          parse(doc_with(R"([{"kind": "set_temperature", "target_c": 5, "ramp_c_per_min": 0}])"))),
      "steps[0].ramp_c_per_min", "0 must be greater than 0");
}

TEST(ValueRules, SoakToleranceMustBePositive) {
  EXPECT_ONE_VIOLATION(
      expand_violations(parse(doc_with(R"([{"kind": "set_temperature", "target_c": 5,
          "soak": {"tolerance_c": 0, "stable_s": 60, "timeout_s": 600}}])"))),
      "steps[0].soak.tolerance_c", "0 must be greater than 0");
}

TEST(ValueRules, SoakStableTimeMustBePositive) {
  EXPECT_ONE_VIOLATION(
      expand_violations(parse(doc_with(R"([{"kind": "set_temperature", "target_c": 5,
          "soak": {"tolerance_c": 1, "stable_s": -60, "timeout_s": 600}}])"))),
      "steps[0].soak.stable_s", "-60 must be greater than 0");
}

TEST(ValueRules, SoakTimeoutMustNotBeShorterThanStableTime) {
  EXPECT_ONE_VIOLATION(
      expand_violations(parse(doc_with(R"([{"kind": "set_temperature", "target_c": 5,
          "soak": {"tolerance_c": 1, "stable_s": "${s}", "timeout_s": 60}}])",
                                       R"({"s": {"default": 300, "description": "d"}})"))),
      "steps[0].soak.timeout_s", "60 is shorter than soak.stable_s ${s} = 300");
}

TEST(ValueRules, MoveAnglesWithinOneTurn) {
  EXPECT_ONE_VIOLATION(expand_violations(parse(
                           doc_with(R"([{"kind": "move", "outer_deg": 400, "inner_deg": -360}])"))),
                       "steps[0].outer_deg", "400 is outside [-360, 360]");
}

TEST(ValueRules, RateMustNotBeZero) {
  EXPECT_ONE_VIOLATION(
      expand_violations(parse(
          doc_with(R"([{"kind": "rate", "axis": "outer", "rate_dps": 0, "duration_s": 5}])"))),
      "steps[0].rate_dps", "0 must not be 0 (record at rest with a capture step)");
}

TEST(ValueRules, SettleTimeMustNotBeNegative) {
  EXPECT_ONE_VIOLATION(
      expand_violations(parse(doc_with(
          R"([{"kind": "rate", "axis": "outer", "rate_dps": 5, "settle_s": -1, "duration_s": 5}])"))),
      "steps[0].settle_s", "-1 must not be negative");
}

TEST(ValueRules, RevolutionsMustBeWhole) {
  EXPECT_ONE_VIOLATION(
      expand_violations(parse(
          doc_with(R"([{"kind": "rate", "axis": "outer", "rate_dps": 5, "revolutions": 1.5}])"))),
      "steps[0].revolutions", "1.5 must be a whole number greater than 0");
}

TEST(ValueRules, LoopValueInANumericFieldMustBeANumber) {
  EXPECT_ONE_VIOLATION(expand_violations(parse(doc_with(
                           R"([{"kind": "for_each", "var": "v", "values": [1, "a"], "steps": [
          {"kind": "wait", "duration_s": "${v}"}]}])"))),
                       "steps[0].steps[0].duration_s", "${v} = \"a\" is not a number");
}

TEST(ValueRules, LoopValueAsAxisMustBeOuterOrInner) {
  EXPECT_ONE_VIOLATION(expand_violations(parse(doc_with(
                           R"([{"kind": "for_each", "var": "v", "values": ["outer", 1], "steps": [
          {"kind": "rate", "axis": "${v}", "rate_dps": 5, "duration_s": 1}]}])"))),
                       "steps[0].steps[0].axis", "${v} = 1 is not \"outer\" or \"inner\"");
}

TEST(ValueRules, LoopOverAnEmptyListParameter) {
  const Procedure p = parse(doc_with(
      R"([{"kind": "for_each", "var": "t", "values": "${temps}", "steps": [{"kind": "wait", "duration_s": 1}]}])",
      R"({"temps": {"default": [25], "description": "d"}})"));
  EXPECT_ONE_VIOLATION(expand_violations(p, {{"temps", json::array()}}), "steps[0].values",
                       "${temps} = [] is empty: the loop would run no steps");
}

TEST(ValueRules, RunawayExpansionIsRefused) {
  json big = json::array();
  for (int i = 0; i < 400; ++i) big.push_back(i + 1);
  json doc = doc_with(R"([{"kind": "for_each", "var": "a", "values": [], "steps": [
      {"kind": "for_each", "var": "b", "values": [], "steps": [{"kind": "wait", "duration_s": 1}]}]}])");
  doc["steps"][0]["values"] = big;
  doc["steps"][0]["steps"][0]["values"] = big;  // 160000 steps
  EXPECT_ONE_VIOLATION(expand_violations(parse(doc)), "steps", "expands to more than 100000 steps");
}

TEST(ValueRules, ARuleBrokenInEveryIterationIsReportedOnce) {
  EXPECT_ONE_VIOLATION(expand_violations(parse(doc_with(
                           R"([{"kind": "for_each", "var": "v", "values": [1, 2, 3], "steps": [
          {"kind": "wait", "duration_s": 0}]}])"))),
                       "steps[0].steps[0].duration_s", "0 must be greater than 0");
}

TEST(ValueRules, EveryViolationIsListed) {
  const auto vs = expand_violations(parse(doc_with(R"([
        {"kind": "for_each", "var": "d", "values": [-1, 5, 0], "steps": [{"kind": "wait", "duration_s": "${d}"}]},
        {"kind": "rate", "axis": "outer", "rate_dps": 0, "revolutions": 2},
        {"kind": "capture", "duration_s": "${c}", "label": "x"}])",
                                                   R"({"c": {"default": 1, "description": "d"}})")),
                                    {{"c", -2}});
  ASSERT_EQ(vs.size(), 4u) << test::lines(vs);
  EXPECT_EQ(vs[0].path, "steps[0].steps[0].duration_s");
  EXPECT_EQ(vs[0].message, "${d} = -1 must be greater than 0");
  EXPECT_EQ(vs[1].message, "${d} = 0 must be greater than 0");
  EXPECT_EQ(vs[2].path, "steps[1].rate_dps");
  EXPECT_EQ(vs[3].path, "steps[2].duration_s");
  EXPECT_EQ(vs[3].message, "${c} = -2 must be greater than 0");
}

}  // namespace
}  // namespace calstand::procedures
