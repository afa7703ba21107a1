// Plan: durations on hand-worked cases, envelope, station-limit rules.
#include "procedures/plan.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "test_util.hpp"

namespace calstand::procedures {
namespace {

using nlohmann::json;
using test::doc_with;
using test::parse;

// Round figures so that every duration below can be worked by hand.
core::StationConfig station() {
  core::StationConfig s;
  s.table.outer.max_rate_dps = 100.0;
  s.table.outer.max_accel_dps2 = 50.0;
  s.table.outer.settle_time_s = 0.5;
  s.table.inner.max_rate_dps = 200.0;
  s.table.inner.max_accel_dps2 = 100.0;
  s.table.inner.settle_time_s = 0.25;
  s.chamber.min_c = -40.0;
  s.chamber.max_c = 85.0;
  s.chamber.max_ramp_c_per_min = 2.0;
  s.chamber.ambient_c = 20.0;
  return s;
}

Plan plan_of(const std::string& steps, const std::string& parameters = "{}",
             const Overrides& overrides = {}) {
  return make_plan(parse(doc_with(steps, parameters)), station(), overrides);
}

TEST(TrapezoidMove, TriangularWhenShortTrapezoidalWhenLong) {
  EXPECT_DOUBLE_EQ(trapezoid_move_s(0.0, 100.0, 50.0), 0.0);
  EXPECT_DOUBLE_EQ(trapezoid_move_s(50.0, 100.0, 50.0), 2.0);   // 2 sqrt(50/50)
  EXPECT_DOUBLE_EQ(trapezoid_move_s(200.0, 100.0, 50.0), 4.0);  // both forms agree at d = v^2/a
  EXPECT_DOUBLE_EQ(trapezoid_move_s(400.0, 100.0, 50.0), 6.0);  // 400/100 + 100/50
}

TEST(PlanDurations, MovesTakeTheSlowerAxisPlusSettleTheShortestWayRound) {
  const Plan p = plan_of(R"([
    {"kind": "move", "outer_deg": 90, "inner_deg": -90},
    {"kind": "move", "outer_deg": 90, "inner_deg": -90},
    {"kind": "move", "outer_deg": 170, "inner_deg": -90},
    {"kind": "move", "outer_deg": -170, "inner_deg": -90}])");
  ASSERT_TRUE(p.ok()) << test::lines(p.violations);
  ASSERT_EQ(p.step_duration_s.size(), 4u);
  // outer 90 deg: 2 sqrt(90/50) = 2.683 s; inner 90 deg: 2 sqrt(90/100) = 1.897 s; settle 0.5.
  EXPECT_NEAR(p.step_duration_s[0], 2.0 * std::sqrt(1.8) + 0.5, 1e-12);
  EXPECT_DOUBLE_EQ(p.step_duration_s[1], 0.0);  // already there
  EXPECT_NEAR(p.step_duration_s[2], 2.0 * std::sqrt(80.0 / 50.0) + 0.5, 1e-12);
  EXPECT_NEAR(p.step_duration_s[3], 2.0 * std::sqrt(20.0 / 50.0) + 0.5, 1e-12);  // 170 -> 190
  EXPECT_NEAR(p.envelope.outer.max_move_rate_dps, std::sqrt(90.0 * 50.0), 1e-12);
  EXPECT_DOUBLE_EQ(p.envelope.inner.max_accel_dps2, 100.0);
  EXPECT_DOUBLE_EQ(p.envelope.outer.max_rate_dps, 0.0);  // no rate step
}

TEST(PlanDurations, RateStepsAccelerateSettleRecordAndStop) {
  const Plan p = plan_of(R"([
    {"kind": "rate", "axis": "outer", "rate_dps": 50, "settle_s": 2, "duration_s": 10},
    {"kind": "rate", "axis": "outer", "rate_dps": 50, "settle_s": 2, "duration_s": 10},
    {"kind": "rate", "axis": "outer", "rate_dps": -50, "settle_s": 2, "duration_s": 10},
    {"kind": "rate", "axis": "inner", "rate_dps": 100, "settle_s": 0, "revolutions": 1}])");
  ASSERT_TRUE(p.ok()) << test::lines(p.violations);
  EXPECT_DOUBLE_EQ(p.step_duration_s[0], 1.0 + 2.0 + 10.0);        // 0 -> 50 at 50 deg/s^2
  EXPECT_DOUBLE_EQ(p.step_duration_s[1], 0.0 + 2.0 + 10.0);        // already at 50
  EXPECT_DOUBLE_EQ(p.step_duration_s[2], 2.0 + 2.0 + 10.0 + 1.0);  // 50 -> -50, then to rest
  EXPECT_DOUBLE_EQ(p.step_duration_s[3], 1.0 + 0.0 + 3.6 + 1.0);   // 360 deg at 100 deg/s
  EXPECT_DOUBLE_EQ(p.step_start_s[3], 13.0 + 12.0 + 15.0);
  EXPECT_DOUBLE_EQ(p.total_s, 13.0 + 12.0 + 15.0 + 5.6);
  EXPECT_DOUBLE_EQ(p.envelope.outer.max_rate_dps, 50.0);
  EXPECT_DOUBLE_EQ(p.envelope.inner.max_rate_dps, 100.0);
  EXPECT_EQ(p.envelope.captures, 4u);
  EXPECT_DOUBLE_EQ(p.envelope.capture_s, 33.6);
}

TEST(PlanDurations, AMoveAfterARateStepStartsFromWhereTheAxisStopped) {
  // 0 -> 50 deg/s in 1 s (25 deg), 1 s at rate (50 deg), 1 s to rest (25 deg): stops at 100 deg.
  const Plan p = plan_of(R"([
    {"kind": "rate", "axis": "outer", "rate_dps": 50, "settle_s": 0, "duration_s": 1},
    {"kind": "move", "outer_deg": 0, "inner_deg": 0}])");
  EXPECT_NEAR(p.step_duration_s[1], trapezoid_move_s(100.0, 100.0, 50.0) + 0.5, 1e-12);
}

TEST(PlanDurations, SoakIsRampPlusStableTimeAndTheChamberKeepsRampingWithoutSoak) {
  const Plan p = plan_of(R"([
    {"kind": "set_temperature", "target_c": -40,
     "soak": {"tolerance_c": 0.5, "stable_s": 600, "timeout_s": 3600}},
    {"kind": "set_temperature", "target_c": 80, "ramp_c_per_min": 1,
     "soak": {"tolerance_c": 0.5, "stable_s": 600, "timeout_s": 3600}},
    {"kind": "set_temperature", "target_c": 20},
    {"kind": "capture", "duration_s": 1200, "label": "ramping"},
    {"kind": "set_temperature", "target_c": 20,
     "soak": {"tolerance_c": 0.5, "stable_s": 300, "timeout_s": 3600}}])");
  ASSERT_TRUE(p.ok()) << test::lines(p.violations);
  EXPECT_DOUBLE_EQ(p.step_duration_s[0], 60.0 / 2.0 * 60.0 + 600.0);   // 20 -> -40 at 2 degC/min
  EXPECT_DOUBLE_EQ(p.step_duration_s[1], 120.0 / 1.0 * 60.0 + 600.0);  // -40 -> 80 at 1 degC/min
  EXPECT_DOUBLE_EQ(p.step_duration_s[2], 0.0);                         // commands, ends at once
  // 80 -> 20 at 2 degC/min takes 1800 s; 1200 s of it pass in the capture, 600 s remain.
  EXPECT_DOUBLE_EQ(p.step_duration_s[4], 600.0 + 300.0);
  EXPECT_DOUBLE_EQ(*p.envelope.min_temperature_c, -40.0);
  EXPECT_DOUBLE_EQ(*p.envelope.max_temperature_c, 80.0);
  EXPECT_DOUBLE_EQ(p.envelope.max_ramp_c_per_min, 2.0);
  EXPECT_DOUBLE_EQ(p.envelope.outer.max_accel_dps2, 0.0);  // table never moves
}

TEST(PlanDurations, CapturesAndWaitsTakeTheirDuration) {
  const Plan p = plan_of(
      R"([{"kind": "wait", "duration_s": 7}, {"kind": "capture", "duration_s": 3, "label": "a"}])");
  EXPECT_DOUBLE_EQ(p.step_start_s[1], 7.0);
  EXPECT_DOUBLE_EQ(p.total_s, 10.0);
  EXPECT_EQ(p.envelope.captures, 1u);
  EXPECT_FALSE(p.envelope.min_temperature_c.has_value());
}

// --- Station limits ----------------------------------------------------------------------------

TEST(StationRules, RateAboveTheAxisLimit) {
  core::StationConfig s = station();
  s.table.outer.max_rate_dps = 200.0;
  const Plan p = make_plan(parse(doc_with(R"([
      {"kind": "wait", "duration_s": 1}, {"kind": "wait", "duration_s": 1}, {"kind": "wait", "duration_s": 1},
      {"kind": "rate", "axis": "outer", "rate_dps": 220, "duration_s": 1}])")),
                           s);
  EXPECT_ONE_VIOLATION(p.violations, "steps[3].rate_dps", "220 exceeds the outer axis limit 200");
}

TEST(StationRules, NegatedReferencedRateAboveTheLimitNamesTheReference) {
  const Plan p =
      plan_of(R"([{"kind": "for_each", "var": "r", "values": "${rates}", "steps": [
      {"kind": "rate", "axis": "inner", "rate_dps": "-${r}", "duration_s": 1}]}])",
              R"({"rates": {"default": [10], "description": "d"}})", {{"rates", json({150, 300})}});
  EXPECT_ONE_VIOLATION(p.violations, "steps[0].steps[0].rate_dps",
                       "-${r} = -300 exceeds the inner axis limit 200");
}

TEST(StationRules, TemperatureOutsideTheChamberRange) {
  EXPECT_ONE_VIOLATION(plan_of(R"([{"kind": "set_temperature", "target_c": 100}])").violations,
                       "steps[0].target_c", "100 is outside the chamber range [-40, 85]");
}

TEST(StationRules, RampAboveTheChamberLimit) {
  EXPECT_ONE_VIOLATION(
      plan_of(R"([{"kind": "set_temperature", "target_c": 0, "ramp_c_per_min": 10}])").violations,
      "steps[0].ramp_c_per_min", "10 exceeds the chamber ramp limit 2");
}

TEST(StationRules, PlanListsOverrideValueAndStationViolationsTogether) {
  const Plan p =
      plan_of(R"([
      {"kind": "capture", "duration_s": "${c}", "label": "a"},
      {"kind": "wait", "duration_s": 0},
      {"kind": "rate", "axis": "outer", "rate_dps": 500, "duration_s": 1}])",
              R"({"c": {"default": 1, "min": 0.5, "description": "d"}})", {{"c", -1}, {"nope", 1}});
  ASSERT_EQ(p.violations.size(), 4u) << test::lines(p.violations);
  EXPECT_FALSE(p.ok());
  try {
    require_valid(p);
    FAIL();
  } catch (const ProcedureError& e) {
    EXPECT_EQ(e.violations().size(), 4u);
    // The rejected override leaves the default, so the capture itself is fine.
    EXPECT_EQ(std::string(e.what()),
              "t.json: --set c: -1 is below the minimum 0.5\n"
              "t.json: --set nope: nope is not a parameter of t (it has c)\n"
              "t.json: steps[1].duration_s: 0 must be greater than 0\n"
              "t.json: steps[2].rate_dps: 500 exceeds the outer axis limit 100");
  }
}

TEST(PlanJson, HoldsStepsEstimatesEnvelopeAndViolations) {
  const Plan p = plan_of(R"([{"kind": "move", "outer_deg": 0, "inner_deg": 90},
                              {"kind": "rate", "axis": "inner", "rate_dps": 250, "duration_s": 2}])");
  const json j = p.to_json();
  EXPECT_EQ(j["procedure"], "t");
  ASSERT_EQ(j["steps"].size(), 2u);
  EXPECT_EQ(j["steps"][1]["kind"], "rate");
  EXPECT_EQ(j["steps"][1]["rate_dps"], 250.0);
  EXPECT_DOUBLE_EQ(j["steps"][1]["estimated_start_s"].get<double>(), p.step_start_s[1]);
  EXPECT_EQ(j["envelope"]["inner"]["max_rate_dps"], 250.0);
  EXPECT_EQ(j["ok"], false);
  EXPECT_EQ(j["violations"][0]["path"], "steps[1].rate_dps");
}

TEST(PlanLimits, APlanLongerThanAYearIsRefusedWithTheReason) {
  const Plan ok = plan_of(R"([{"kind": "capture", "label": "a day", "duration_s": 86400}])");
  EXPECT_TRUE(ok.ok()) << test::lines(ok.violations);
  const Plan absurd = plan_of(
      R"([{"kind": "capture", "label": "c", "duration_s": "${capture_s}"}])",
      R"({"capture_s": {"default": 1, "min": 1, "description": "s"}})", {{"capture_s", 1e308}});
  ASSERT_FALSE(absurd.ok());
  ASSERT_EQ(absurd.violations.size(), 1u) << test::lines(absurd.violations);
  EXPECT_EQ(absurd.violations[0].path, "procedure");
  EXPECT_NE(absurd.violations[0].message.find("more than a year"), std::string::npos);
}

}  // namespace
}  // namespace calstand::procedures

namespace calstand::procedures {
namespace {

// The round-figure station with two IMUs: "a" as mounted, "b" turned 90 deg about z.
core::StationConfig station_with_imus() {
  core::StationConfig s = station();
  s.name = "bench";
  s.imus.resize(2);
  s.imus[0].name = "a";
  s.imus[1].name = "b";
  s.imus[1].mount_rpy_deg = Eigen::Vector3d(0, 0, 90);
  return s;
}

TEST(PlanPointing, UpIsResolvedForTheTableAndTheNamedImusMount) {
  const core::StationConfig s = station_with_imus();
  const Plan p = make_plan(parse(doc_with(R"([
    {"kind": "for_each", "var": "d", "values": ["+x", "-y"], "steps": [
      {"kind": "move", "up": "${d}"},
      {"kind": "move", "up": "${d}", "imu": "b"}]}])")),
                           s);
  ASSERT_TRUE(p.ok()) << test::lines(p.violations);
  ASSERT_EQ(p.steps.size(), 4u);
  for (const Step& step : p.steps) {
    const std::size_t imu = step.imu == "b" ? 1 : 0;
    const int axis = step.up[1] - 'x';
    const double sign = step.up[0] == '+' ? 1.0 : -1.0;
    const Eigen::Vector3d up_in_body =
        s.geometry(imu).body_to_level(step.outer_deg, step.inner_deg).transpose() *
        Eigen::Vector3d::UnitZ();
    EXPECT_NEAR((up_in_body - sign * Eigen::Vector3d::Unit(axis)).norm(), 0.0, 1e-9)
        << step.label << " imu " << imu;
    EXPECT_EQ(step.label, "point " + step.up + " up");
    EXPECT_EQ(step.to_json()["up"], step.up);
  }
  // The mounts differ by 90 deg of yaw: body x of "b" is not where body x of "a" is.
  EXPECT_FALSE(p.steps[0].outer_deg == p.steps[1].outer_deg &&
               p.steps[0].inner_deg == p.steps[1].inner_deg);
  EXPECT_EQ(p.steps[0].references.at("up"), "${d}");
}

TEST(PlanPointing, AnUnknownImuOrAStationWithoutImusIsAViolationOfTheStep) {
  const Procedure proc = parse(doc_with(R"([{"kind": "wait", "duration_s": 1},
    {"kind": "move", "up": "+z", "imu": "c"}])"));
  EXPECT_ONE_VIOLATION(make_plan(proc, station_with_imus()).violations, "steps[1].imu",
                       "\"c\" is not an IMU of station \"bench\"");
  const Procedure first = parse(doc_with(R"([{"kind": "move", "up": "+z"}])"));
  EXPECT_ONE_VIOLATION(make_plan(first, station()).violations, "steps[0].up",
                       "the station has no IMU to point");
}

TEST(PlanPower, APowerStepTakesItsSettleTimeAndNeedsASupplyForItsUnit) {
  core::StationConfig with = station();
  with.imus.push_back({});
  with.imus.back().name = "imu0";
  core::PowerSupplyConfig psu;
  psu.name = "psu0";
  psu.imu = "imu0";
  with.power_supplies.push_back(psu);
  const std::string steps =
      R"([{"kind": "power", "power": "off", "settle_s": 5},
          {"kind": "power", "power": "on", "settle_s": 30, "imu": "imu0"}])";
  const Plan ok = make_plan(parse(doc_with(steps)), with, {});
  EXPECT_TRUE(ok.violations.empty());
  ASSERT_EQ(ok.steps.size(), 2u);
  EXPECT_EQ(ok.steps[1].kind, StepKind::kPower);
  EXPECT_TRUE(ok.steps[1].power_on);
  EXPECT_DOUBLE_EQ(ok.step_duration_s[0], 5.0);
  EXPECT_DOUBLE_EQ(ok.step_duration_s[1], 30.0);
  EXPECT_EQ(ok.steps[1].to_json()["power"], "on");

  const Plan none = plan_of(steps);  // a station without supplies
  ASSERT_EQ(none.violations.size(), 2u);
  EXPECT_EQ(none.violations[0].path, "steps[0].power");
  EXPECT_EQ(none.violations[1].path, "steps[1].imu");
  EXPECT_NE(none.violations[1].message.find("no power supply for IMU \"imu0\""), std::string::npos);
}

// Outer axis 100 deg/s, 50 deg/s^2: 1 deg at 1 Hz peaks at 6.28 deg/s and 39.5 deg/s^2 (within);
// at 2 Hz at 158 deg/s^2 (beyond the acceleration only); 20 deg at 1 Hz at 125.7 deg/s (beyond
// both).
TEST(PlanOscillate, TakesSettleAndRecordedCyclesAndRefusesASineBeyondTheAxisNamingTheStep) {
  const Plan ok = plan_of(R"([{"kind": "oscillate", "axis": "outer", "amplitude_deg": 1,
                               "frequency_hz": 1, "cycles": 10, "settle_cycles": 3}])");
  ASSERT_TRUE(ok.ok()) << test::lines(ok.violations);
  EXPECT_EQ(ok.steps[0].kind, StepKind::kOscillate);
  EXPECT_DOUBLE_EQ(ok.steps[0].duration_s, 10.0);
  EXPECT_DOUBLE_EQ(ok.step_duration_s[0], 3.0 + 10.0 + 0.5);  // settle, record, back at rest
  EXPECT_NEAR(ok.envelope.outer.max_rate_dps, 2.0 * M_PI, 1e-12);
  EXPECT_EQ(ok.envelope.captures, 1u);
  EXPECT_EQ(ok.steps[0].to_json()["kind"], "oscillate");

  const Plan fast = plan_of(R"([{"kind": "wait", "duration_s": 1},
      {"kind": "oscillate", "axis": "${a}", "amplitude_deg": 1, "frequency_hz": "${f}",
       "cycles": 10}])",
                            R"({"a": {"default": "outer", "description": "axis"},
                                "f": {"default": 2, "description": "Hz"}})");
  ASSERT_EQ(fast.violations.size(), 1u) << test::lines(fast.violations);
  EXPECT_EQ(fast.violations[0].path, "steps[1].amplitude_deg");
  EXPECT_NE(fast.violations[0].message.find("above the outer axis acceleration limit 50"),
            std::string::npos)
      << fast.violations[0].message;
  EXPECT_NE(fast.violations[0].message.find("${f} = 2 Hz"), std::string::npos)
      << fast.violations[0].message;
  // The default settle is two periods.
  EXPECT_DOUBLE_EQ(fast.step_duration_s[1], 2.0 / 2.0 + 10.0 / 2.0 + 0.5);

  const Plan wide = plan_of(R"([{"kind": "oscillate", "axis": "outer", "amplitude_deg": 20,
                                 "frequency_hz": 1, "cycles": 1}])");
  ASSERT_EQ(wide.violations.size(), 2u) << test::lines(wide.violations);
  EXPECT_NE(wide.violations[0].message.find("above the outer axis rate limit 100"),
            std::string::npos);
  // The inner axis has room for the same sine: the limits are the named axis's.
  EXPECT_TRUE(plan_of(R"([{"kind": "oscillate", "axis": "inner", "amplitude_deg": 1,
                           "frequency_hz": 1.5, "cycles": 1}])")
                  .ok());
}

TEST(PlanOscillate, ValueRulesNameTheField) {
  const Procedure p = parse(doc_with(R"([{"kind": "oscillate", "axis": "outer",
      "amplitude_deg": 0, "frequency_hz": -1, "cycles": 2.5}])"));
  const auto v = make_plan(p, station()).violations;
  ASSERT_EQ(v.size(), 3u) << test::lines(v);
  EXPECT_EQ(v[0].path, "steps[0].amplitude_deg");
  EXPECT_EQ(v[1].path, "steps[0].frequency_hz");
  EXPECT_EQ(v[2].path, "steps[0].cycles");
}

}  // namespace
}  // namespace calstand::procedures
