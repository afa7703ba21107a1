// The shipped procedures: each loads, expands and fits the default station; the static tests'
// orientations really put the body axes where their labels say (checked with TableGeometry).
#include "procedures/library.hpp"

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <cmath>
#include <map>
#include <numbers>
#include <optional>
#include <set>

#include "core/table_geometry.hpp"
#include "procedures/plan.hpp"
#include "procedures/procedure.hpp"
#include "sim/sim_world.hpp"
#include "test_util.hpp"

namespace calstand::procedures {
namespace {

using nlohmann::json;

const core::StationConfig& default_station() {
  static const core::StationConfig s = sim::default_station();
  return s;
}

// Each capture's label with the table angles of the move before it.
struct Pose {
  std::string label;
  double outer_deg;
  double inner_deg;
};

std::vector<Pose> capture_poses(const std::vector<Step>& steps) {
  std::vector<Pose> poses;
  for (std::size_t i = 1; i < steps.size(); ++i) {
    if (steps[i].kind != StepKind::kCapture) continue;
    EXPECT_EQ(steps[i - 1].kind, StepKind::kMove) << steps[i].label;
    poses.push_back({steps[i].label, steps[i - 1].outer_deg, steps[i - 1].inner_deg});
  }
  return poses;
}

Eigen::Vector3d body_axis_in_level(const Pose& p, char axis, const core::TableGeometry& g) {
  return g.body_to_level(p.outer_deg, p.inner_deg).col(axis - 'x');
}

void expect_points(const Pose& p, char axis, const Eigen::Vector3d& direction,
                   const core::TableGeometry& g = default_station().geometry(0)) {
  const Eigen::Vector3d got = body_axis_in_level(p, axis, g);
  EXPECT_NEAR((got - direction).norm(), 0.0, 1e-9)
      << p.label << ": body " << axis << " points " << got.transpose() << " (outer " << p.outer_deg
      << ", inner " << p.inner_deg << ")";
}

const Eigen::Vector3d kUp(0, 0, 1), kDown(0, 0, -1), kNorth(0, 1, 0), kSouth(0, -1, 0);

TEST(Library, ShipsTheStandardProcedures) {
  const std::vector<std::string> want{"bandwidth",    "first-look",          "multi-position",
                                      "rate-ladder",  "repeatability",       "six-position",
                                      "static-allan", "thermal-calibration", "thermal-hysteresis",
                                      "thermal-ramp", "twelve-position",     "two-position",
                                      "warm-up"};
  EXPECT_EQ(library_names(), want);
  EXPECT_FALSE(library_text("no-such-procedure").has_value());
  EXPECT_FALSE(library_text("../six-position").has_value());
}

TEST(Library, EveryProcedureLoadsExpandsAndFitsTheDefaultStation) {
  for (const auto& name : library_names()) {
    SCOPED_TRACE(name);
    const Procedure p = load_procedure(name);
    EXPECT_EQ(p.name, name);
    EXPECT_FALSE(p.description.empty());
    for (const auto& [param, spec] : p.parameter_specs)
      EXPECT_FALSE(spec.description.empty()) << param;
    const Plan plan = make_plan(p, default_station());
    EXPECT_TRUE(plan.ok()) << test::lines(plan.violations);
    EXPECT_FALSE(plan.steps.empty());
    EXPECT_GT(plan.envelope.captures, 0u);
    EXPECT_GT(plan.total_s, plan.envelope.capture_s - 1e-9);
  }
}

// The steps as the plan resolves them for `station`: moves given by pointing get their angles.
std::vector<Step> planned(const std::string& name,
                          const core::StationConfig& station = default_station()) {
  const Plan plan = make_plan(load_procedure(name), station);
  EXPECT_TRUE(plan.ok()) << test::lines(plan.violations);
  return plan.steps;
}

TEST(Library, TwoPositionTurnsBodyZUpThenDown) {
  const auto poses = capture_poses(planned("two-position"));
  ASSERT_EQ(poses.size(), 2u);
  expect_points(poses[0], 'z', kUp);
  expect_points(poses[1], 'z', kDown);
}

// Each capture of a six-position-like procedure points the body axis its label names.
void expect_six_positions(const std::vector<Step>& steps, const core::TableGeometry& g) {
  const auto poses = capture_poses(steps);
  ASSERT_EQ(poses.size(), 6u);
  std::set<std::string> seen;
  for (const auto& pose : poses) {
    const char axis = pose.label[0];  // "x up", "y down"...
    const bool up = pose.label.substr(1) == " up";
    ASSERT_TRUE(up || pose.label.substr(1) == " down") << pose.label;
    expect_points(pose, axis, up ? kUp : kDown, g);
    seen.insert(pose.label);
  }
  EXPECT_EQ(seen, (std::set<std::string>{"x up", "x down", "y up", "y down", "z up", "z down"}));
}

TEST(Library, SixPositionPutsEachBodyAxisUpAndDown) {
  expect_six_positions(planned("six-position"), default_station().geometry(0));
}

TEST(Library, SixPositionFindsItsAnglesForTheStationsTableAndMount) {
  // Outer axis East instead of North, and the IMU turned 90 deg on the platform: the default
  // table's angles would point the wrong axes up.
  core::StationConfig station = default_station();
  station.table.outer_axis = Eigen::Vector3d(1, 0, 0);
  station.imus.at(0).mount_rpy_deg = Eigen::Vector3d(0, 0, 90);
  const auto steps = planned("six-position", station);
  expect_six_positions(steps, station.geometry(0));
  const auto defaults = planned("six-position");
  bool differs = false;
  for (std::size_t i = 0; i < steps.size(); ++i) {
    differs |=
        steps[i].outer_deg != defaults[i].outer_deg || steps[i].inner_deg != defaults[i].inner_deg;
  }
  EXPECT_TRUE(differs) << "the east table needs other angles than the default one";
}

TEST(Library, ATableThatCannotPointAnAxisUpRefusesThePlanNamingTheStep) {
  // Outer axis vertical, inner axis East: body x (East at zero) stays horizontal whatever the
  // angles, so "x up" does not exist.
  core::StationConfig station = default_station();
  station.table.outer_axis = Eigen::Vector3d(0, 0, 1);
  station.table.inner_axis = Eigen::Vector3d(1, 0, 0);
  const Plan plan = make_plan(load_procedure("six-position"), station);
  ASSERT_FALSE(plan.ok());
  const std::string text = test::lines(plan.violations);
  EXPECT_NE(text.find("steps[4].up: the table cannot point body axis +x up"), std::string::npos)
      << text;
  EXPECT_NE(text.find("steps[6].up: the table cannot point body axis -x up"), std::string::npos)
      << text;
  EXPECT_EQ(text.find("steps[0].up"), std::string::npos) << "z up exists: " << text;
}

TEST(Library, SixPositionCapturesAreTheOverriddenLength) {
  const auto steps = expand(load_procedure("six-position"), parse_overrides({"capture_s=15"}));
  ASSERT_EQ(steps.size(), 12u);
  for (const auto& s : steps) {
    if (s.kind == StepKind::kCapture) {
      EXPECT_DOUBLE_EQ(s.duration_s, 15.0);
    }
  }
}

TEST(Library, TwelvePositionPutsEachAxisUpAndDownAtTwoOppositeHeadings) {
  // Labels read "<axis> <up|down>, <other axis> <north|south>".
  const auto poses = capture_poses(expand(load_procedure("twelve-position")));
  ASSERT_EQ(poses.size(), 12u);
  std::set<std::string> seen;
  for (const auto& pose : poses) {
    const std::string& l = pose.label;
    const char axis = l[0];
    const bool up = l.find(" up,") != std::string::npos;
    const char other = l[l.find(", ") + 2];
    const bool north = l.find("north") != std::string::npos;
    expect_points(pose, axis, up ? kUp : kDown);
    expect_points(pose, other, north ? kNorth : kSouth);
    seen.insert(l);
  }
  EXPECT_EQ(seen.size(), 12u);
}

TEST(Library, MultiPositionHasTwentyFourDistinctMostlyTiltedOrientations) {
  const auto poses = capture_poses(expand(load_procedure("multi-position")));
  ASSERT_GE(poses.size(), 24u);
  std::vector<Eigen::Vector3d> gravity_in_body;
  int tilted = 0;
  for (const auto& pose : poses) {
    const core::TableGeometry g = default_station().geometry(0);
    const Eigen::Vector3d up_b = g.body_to_level(pose.outer_deg, pose.inner_deg).transpose() * kUp;
    // Tilted: no body axis within 1 deg of the vertical.
    if (up_b.cwiseAbs().maxCoeff() < std::cos(std::numbers::pi / 180.0)) ++tilted;
    gravity_in_body.push_back(up_b);
  }
  EXPECT_GE(tilted, 8);
  std::size_t distinct_gravity = 0;
  for (std::size_t i = 0; i < gravity_in_body.size(); ++i) {
    bool repeated = false;
    for (std::size_t j = 0; j < i; ++j)
      repeated |= (gravity_in_body[i] - gravity_in_body[j]).norm() < 1e-6;
    if (!repeated) ++distinct_gravity;
  }
  // Distinct gravity directions in the body (several poses differ only in heading).
  EXPECT_GE(distinct_gravity, 18u);
}

// The body axis (a letter) and signed body rate of each rate step, from the table angles the
// moves before it left (TableGeometry): the outer axis turns about a body axis that depends on
// the inner angle, so the inner angle must be known at each outer rate step.
struct BodyRotation {
  char axis;
  double rate_dps;
  double duration_s;
};

std::vector<BodyRotation> body_rotations(const std::vector<Step>& steps) {
  const core::TableGeometry g = default_station().geometry(0);
  std::optional<double> outer, inner;  // unknown after a rate step on that axis
  std::vector<BodyRotation> out;
  for (const auto& s : steps) {
    if (s.kind == StepKind::kMove) {
      outer = s.outer_deg;
      inner = s.inner_deg;
    }
    if (s.kind != StepKind::kRate) continue;
    const bool on_outer = s.axis == "outer";
    EXPECT_TRUE(!on_outer || inner.has_value()) << s.label << ": inner angle unknown";
    const double o = outer.value_or(0.0), i = inner.value_or(0.0);
    const Eigen::Vector3d level =
        g.table_rate_level_dps(o, on_outer ? s.rate_dps : 0.0, on_outer ? 0.0 : s.rate_dps);
    const Eigen::Vector3d body = g.body_to_level(o, i).transpose() * level;
    Eigen::Index k = 0;
    body.cwiseAbs().maxCoeff(&k);
    EXPECT_NEAR(std::abs(body[k]), std::abs(s.rate_dps), 1e-9)
        << s.label << ": about " << body.transpose();
    out.push_back({static_cast<char>('x' + k), body[k], s.duration_s});
    (on_outer ? outer : inner).reset();
  }
  return out;
}

TEST(Library, RateLadderTurnsEachRateBothWaysAboutEachBodyAxisForWholeRevolutions) {
  const auto steps = expand(load_procedure("rate-ladder"));
  for (const auto& s : steps) {
    if (s.kind != StepKind::kRate) continue;
    ASSERT_TRUE(s.revolutions.has_value()) << s.label;
    EXPECT_NEAR(s.duration_s * std::abs(s.rate_dps), 360.0 * *s.revolutions, 1e-9) << s.label;
  }
  std::map<std::pair<char, double>, double> recorded_s;  // (body axis, body rate) -> time
  const auto rotations = body_rotations(steps);
  for (const auto& r : rotations) recorded_s[{r.axis, r.rate_dps}] += r.duration_s;
  for (const char axis : {'x', 'y', 'z'}) {
    for (const double rate : {10.0, 30.0, 100.0, 300.0}) {
      ASSERT_EQ(recorded_s.count({axis, rate}), 1u) << axis << " " << rate;
      ASSERT_EQ(recorded_s.count({axis, -rate}), 1u) << axis << " " << -rate;
      const double cw_s = recorded_s[{axis, rate}], ccw_s = recorded_s[{axis, -rate}];
      EXPECT_DOUBLE_EQ(cw_s, ccw_s);
    }
  }
  EXPECT_EQ(rotations.size(), 24u);  // each (axis, rate) once
}

TEST(Library, RateLadderInAnyAxisOrderStillTurnsAboutEachBodyAxis) {
  const auto steps = expand(load_procedure("rate-ladder"),
                            parse_overrides({R"(axes=["inner","outer"])", "rates=[30]"}));
  std::set<std::pair<char, double>> seen;
  for (const auto& r : body_rotations(steps)) seen.insert({r.axis, r.rate_dps});
  EXPECT_EQ(seen, (std::set<std::pair<char, double>>{
                      {'x', 30}, {'x', -30}, {'y', 30}, {'y', -30}, {'z', 30}, {'z', -30}}));
}

TEST(Library, RateLadderAboveTheStationLimitIsReportedPerRate) {
  const Plan plan = make_plan(load_procedure("rate-ladder"), default_station(),
                              parse_overrides({"rates=[100,600]"}));
  // 600 deg/s exceeds the outer axis (400) but not the inner one (1000); both signs, in the
  // ladder with body z up and in the one about body x.
  ASSERT_EQ(plan.violations.size(), 4u) << test::lines(plan.violations);
  EXPECT_EQ(plan.violations[0].path, "steps[0].steps[1].steps[0].rate_dps");
  EXPECT_EQ(plan.violations[0].message, "${rate} = 600 exceeds the outer axis limit 400");
  EXPECT_EQ(plan.violations[1].message, "-${rate} = -600 exceeds the outer axis limit 400");
  EXPECT_EQ(plan.violations[2].path, "steps[2].steps[0].rate_dps");
  EXPECT_EQ(plan.violations[3].path, "steps[2].steps[1].rate_dps");
}

TEST(Library, ThermalCalibrationSoaksEachOverriddenPlateau) {
  const Procedure p = load_procedure("thermal-calibration");
  const Plan plan = make_plan(p, default_station(), parse_overrides({"temperatures=[-40,25,85]"}));
  ASSERT_TRUE(plan.ok()) << test::lines(plan.violations);
  std::vector<double> soaks;
  for (const auto& s : plan.steps) {
    if (s.kind == StepKind::kSetTemperature && s.wait_for_soak) soaks.push_back(s.target_c);
  }
  EXPECT_EQ(soaks, (std::vector<double>{-40, 25, 85, 25}));  // plateaus, then back to final_c
  EXPECT_DOUBLE_EQ(*plan.envelope.min_temperature_c, -40.0);
  EXPECT_DOUBLE_EQ(*plan.envelope.max_temperature_c, 85.0);
  // Per plateau: 24 orientations and 3 body axes x 4 rates x 2 directions.
  EXPECT_EQ(plan.envelope.captures, 3u * (24u + 24u));
  EXPECT_GT(plan.total_s, 3 * 1800.0);
}

TEST(Library, ThermalCalibrationLadderTurnsAboutEachBodyAxisOnEachPlateau) {
  const auto steps = expand(load_procedure("thermal-calibration"),
                            parse_overrides({"temperatures=[-10,60]", "rates=[30,100]"}));
  std::map<std::pair<char, double>, int> turns;  // (body axis, body rate) -> plateaus
  for (const auto& r : body_rotations(steps)) ++turns[{r.axis, r.rate_dps}];
  ASSERT_EQ(turns.size(), 3u * 2u * 2u);
  for (const auto& [key, plateaus] : turns)
    EXPECT_EQ(plateaus, 2) << key.first << " " << key.second;
}

// Each ramp (a set_temperature that does not soak, up to the soak at its end) is covered by
// the rotation cycles: every cycle points each body axis up and down and turns about each body
// axis both ways, so every temperature of the ramp sees the whole classical model.
TEST(Library, ThermalRampIndexesAndTurnsThroughEachRampWhileTheChamberRamps) {
  const Plan plan = make_plan(load_procedure("thermal-ramp"), default_station());
  ASSERT_TRUE(plan.ok()) << test::lines(plan.violations);
  const core::TableGeometry g = default_station().geometry(0);
  constexpr int kCycles = 31;
  const double ramp_s = 60.0 * (85.0 - -40.0) / 1.0;
  int ramps = 0;
  for (std::size_t i = 0; i < plan.steps.size(); ++i) {
    const Step& start = plan.steps[i];
    if (start.kind != StepKind::kSetTemperature || start.wait_for_soak) continue;
    ++ramps;
    std::size_t end = i + 1;
    double recorded_through_s = 0.0;
    for (; end < plan.steps.size() && plan.steps[end].kind != StepKind::kSetTemperature; ++end)
      recorded_through_s += plan.step_duration_s[end];
    ASSERT_LT(end, plan.steps.size()) << start.label << ": no soak after the ramp";
    EXPECT_TRUE(plan.steps[end].wait_for_soak)
        << "the step after the ramp: " << plan.steps[end].label;
    // The cycles cover the ramp and stop within one cycle of its end.
    const double cycle_s = recorded_through_s / kCycles;
    EXPECT_GE(recorded_through_s, ramp_s) << start.label;
    EXPECT_LT(recorded_through_s, ramp_s + cycle_s) << start.label;

    std::map<std::string, int> poses;  // body direction up -> captures
    std::map<std::pair<char, double>, int> turns;
    std::vector<Step> ramp_steps(plan.steps.begin() + static_cast<std::ptrdiff_t>(i + 1),
                                 plan.steps.begin() + static_cast<std::ptrdiff_t>(end));
    for (const auto& r : body_rotations(ramp_steps)) ++turns[{r.axis, r.rate_dps}];
    double outer = 0.0, inner = 0.0;
    for (const Step& s : ramp_steps) {
      if (s.kind == StepKind::kMove) {
        outer = s.outer_deg;
        inner = s.inner_deg;
      }
      if (s.kind != StepKind::kCapture) continue;
      const Eigen::Vector3d up =
          g.body_to_level(outer, inner).transpose() * Eigen::Vector3d::UnitZ();
      Eigen::Index k = 0;
      up.cwiseAbs().maxCoeff(&k);
      EXPECT_NEAR(std::abs(up[k]), 1.0, 1e-9) << s.label;
      ++poses[std::string(up[k] > 0 ? "+" : "-") + static_cast<char>('x' + k)];
    }
    EXPECT_EQ(poses, (std::map<std::string, int>{{"+x", kCycles},
                                                 {"-x", kCycles},
                                                 {"+y", kCycles},
                                                 {"-y", kCycles},
                                                 {"+z", kCycles},
                                                 {"-z", kCycles}}))
        << start.label;
    EXPECT_EQ(turns, (std::map<std::pair<char, double>, int>{{{'x', 60}, kCycles},
                                                             {{'x', -60}, kCycles},
                                                             {{'y', 60}, kCycles},
                                                             {{'y', -60}, kCycles},
                                                             {{'z', 60}, kCycles},
                                                             {{'z', -60}, kCycles}}))
        << start.label;
  }
  EXPECT_EQ(ramps, 2);  // heating and cooling
}

TEST(Library, StaticAllanIsOneLongCapture) {
  const Plan plan = make_plan(load_procedure("static-allan"), default_station());
  ASSERT_EQ(plan.envelope.captures, 1u);
  EXPECT_GE(plan.envelope.capture_s, 3.0 * 3600.0);
  EXPECT_DOUBLE_EQ(plan.envelope.outer.max_rate_dps, 0.0);
  EXPECT_DOUBLE_EQ(plan.envelope.inner.max_rate_dps, 0.0);
}

}  // namespace
}  // namespace calstand::procedures
