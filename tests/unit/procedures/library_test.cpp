// The shipped procedures: each loads, expands and fits the default station; the static tests'
// orientations really put the body axes where their labels say (checked with TableGeometry).
#include "procedures/library.hpp"

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <cmath>
#include <map>
#include <numbers>
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

Eigen::Vector3d body_axis_in_level(const Pose& p, char axis) {
  const core::TableGeometry g = default_station().geometry(0);
  return g.body_to_level(p.outer_deg, p.inner_deg).col(axis - 'x');
}

void expect_points(const Pose& p, char axis, const Eigen::Vector3d& direction) {
  const Eigen::Vector3d got = body_axis_in_level(p, axis);
  EXPECT_NEAR((got - direction).norm(), 0.0, 1e-9)
      << p.label << ": body " << axis << " points " << got.transpose() << " (outer " << p.outer_deg
      << ", inner " << p.inner_deg << ")";
}

const Eigen::Vector3d kUp(0, 0, 1), kDown(0, 0, -1), kNorth(0, 1, 0), kSouth(0, -1, 0);

TEST(Library, ShipsTheStandardProcedures) {
  const std::vector<std::string> want{"multi-position",  "rate-ladder",         "six-position",
                                      "static-allan",    "thermal-calibration", "thermal-ramp",
                                      "twelve-position", "two-position"};
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

TEST(Library, TwoPositionTurnsBodyZUpThenDown) {
  const auto poses = capture_poses(expand(load_procedure("two-position")));
  ASSERT_EQ(poses.size(), 2u);
  expect_points(poses[0], 'z', kUp);
  expect_points(poses[1], 'z', kDown);
}

TEST(Library, SixPositionPutsEachBodyAxisUpAndDown) {
  const auto poses = capture_poses(expand(load_procedure("six-position")));
  ASSERT_EQ(poses.size(), 6u);
  std::set<std::string> seen;
  for (const auto& pose : poses) {
    const char axis = pose.label[0];  // "x up", "y down"...
    const bool up = pose.label.substr(1) == " up";
    ASSERT_TRUE(up || pose.label.substr(1) == " down") << pose.label;
    expect_points(pose, axis, up ? kUp : kDown);
    seen.insert(pose.label);
  }
  EXPECT_EQ(seen, (std::set<std::string>{"x up", "x down", "y up", "y down", "z up", "z down"}));
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

TEST(Library, RateLadderTurnsEachRateBothWaysOnEachAxisForWholeRevolutions) {
  const auto steps = expand(load_procedure("rate-ladder"));
  std::map<std::pair<std::string, double>, double> recorded_s;  // (axis, rate) -> time
  for (const auto& s : steps) {
    if (s.kind != StepKind::kRate) continue;
    ASSERT_TRUE(s.revolutions.has_value());
    EXPECT_NEAR(s.duration_s * std::abs(s.rate_dps), 360.0 * *s.revolutions, 1e-9);
    recorded_s[{s.axis, s.rate_dps}] = s.duration_s;
  }
  for (const std::string axis : {"outer", "inner"}) {
    for (const double rate : {10.0, 30.0, 100.0, 300.0}) {
      ASSERT_EQ(recorded_s.count({axis, rate}), 1u) << axis << " " << rate;
      ASSERT_EQ(recorded_s.count({axis, -rate}), 1u) << axis << " " << -rate;
      const double cw_s = recorded_s[{axis, rate}], ccw_s = recorded_s[{axis, -rate}];
      EXPECT_DOUBLE_EQ(cw_s, ccw_s);
    }
  }
  EXPECT_EQ(recorded_s.size(), 16u);
}

TEST(Library, RateLadderAboveTheStationLimitIsReportedPerRate) {
  const Plan plan = make_plan(load_procedure("rate-ladder"), default_station(),
                              parse_overrides({"rates=[100,600]"}));
  // 600 deg/s exceeds the outer axis (400) but not the inner one (1000); both signs.
  ASSERT_EQ(plan.violations.size(), 2u) << test::lines(plan.violations);
  EXPECT_EQ(plan.violations[0].path, "steps[1].steps[0].steps[0].rate_dps");
  EXPECT_EQ(plan.violations[0].message, "${rate} = 600 exceeds the outer axis limit 400");
  EXPECT_EQ(plan.violations[1].message, "-${rate} = -600 exceeds the outer axis limit 400");
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
  // Per plateau: 24 orientations and 2 axes x 4 rates x 2 directions.
  EXPECT_EQ(plan.envelope.captures, 3u * (24u + 16u));
  EXPECT_GT(plan.total_s, 3 * 1800.0);
}

TEST(Library, ThermalRampRecordsWhileTheChamberRamps) {
  const Procedure p = load_procedure("thermal-ramp");
  const Plan plan = make_plan(p, default_station());
  std::size_t ramp_captures = 0, soaks_at_ramp_end = 0;
  for (std::size_t i = 1; i + 1 < plan.steps.size(); ++i) {
    const Step& before = plan.steps[i - 1];
    if (plan.steps[i].kind == StepKind::kCapture && before.kind == StepKind::kSetTemperature &&
        !before.wait_for_soak) {
      ++ramp_captures;
      // The default capture covers the whole ramp: 60 * (85 - -40) / 0.5 s.
      EXPECT_DOUBLE_EQ(plan.steps[i].duration_s, 60.0 * 125.0 / 0.5);
      // ... so a soak at the ramp's end right after it needs only its stable time.
      const Step& after = plan.steps[i + 1];
      if (after.target_c == before.target_c) {
        EXPECT_DOUBLE_EQ(plan.step_duration_s[i + 1], after.soak.stable_s);
        ++soaks_at_ramp_end;
      }
    }
  }
  EXPECT_EQ(ramp_captures, 2u);
  EXPECT_EQ(soaks_at_ramp_end, 1u);  // the top; after the ramp down the chamber goes to final_c
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
