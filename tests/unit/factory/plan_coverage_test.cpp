// What a procedure determines for each unit of a fixture, checked at plan time against the
// physics: which body axes see gravity or the table's rotation at each unit's mount.
#include "factory/plan_coverage.hpp"

#include <gtest/gtest.h>

#include <set>

#include "procedures/procedure.hpp"
#include "sim/sim_world.hpp"

namespace calstand::analysis {
namespace {

std::set<std::string> undetermined_of(const UnitCoverage& unit, const std::string& prefix) {
  std::set<std::string> out;
  for (const auto& p : unit.undetermined) {
    if (p.name.rfind(prefix, 0) == 0) out.insert(p.name);
  }
  return out;
}

core::StationConfig fixture(const std::vector<Eigen::Vector3d>& mounts_rpy_deg) {
  core::StationConfig station = sim::default_station();
  const core::ImuConfig base = station.imus.at(0);
  station.imus.clear();
  for (std::size_t i = 0; i < mounts_rpy_deg.size(); ++i) {
    core::ImuConfig imu = base;
    imu.name = "imu" + std::to_string(i);
    imu.mount_rpy_deg = mounts_rpy_deg[i];
    station.imus.push_back(imu);
  }
  return station;
}

// The rate ladder keeps the table level and turns it about the vertical: gravity stays on the
// body axis that the mount puts vertical, so only that accelerometer axis's scale factor is
// determined, and a unit rolled 90 deg has y there instead of z.
TEST(PlanCoverage, ALevelRateLadderDeterminesTheScaleOfTheAccelerometerAxisEachMountPutsVertical) {
  const core::StationConfig station =
      fixture({Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(90, 0, 0), Eigen::Vector3d(0, 0, 90)});
  const auto plan = procedures::make_plan(procedures::load_procedure("rate-ladder"), station);
  const auto coverage =
      plan_coverage(plan, station, solver::Model::parse("accel_bias,accel_scale,gyro_bias"));
  ASSERT_EQ(coverage.units.size(), 3u);
  EXPECT_EQ(undetermined_of(coverage.units[0], "accel_scale"),
            (std::set<std::string>{"accel_scale.x", "accel_scale.y"}));
  EXPECT_EQ(undetermined_of(coverage.units[1], "accel_scale"),
            (std::set<std::string>{"accel_scale.x", "accel_scale.z"}));
  // A yaw about the vertical keeps z vertical: the same as the unrotated unit.
  EXPECT_EQ(undetermined_of(coverage.units[2], "accel_scale"),
            (std::set<std::string>{"accel_scale.x", "accel_scale.y"}));
  for (const auto& u : coverage.units) {
    EXPECT_TRUE(undetermined_of(u, "accel_bias").empty()) << u.imu;
    EXPECT_GT(u.recording_steps, 0u);
  }
}

// Six positions point each body axis of the first unit up and down: every accelerometer term of
// every unit is determined whatever its mount (they are all right-angle mounts), while the gyro
// scale factors are not (the Earth rate alone is too small against LN200-class noise), as the
// procedure's description says.
TEST(PlanCoverage, SixPositionsDetermineTheAccelerometerOfEveryRightAngleMountButNoGyroScale) {
  const core::StationConfig station =
      fixture({Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(0, 90, 0)});
  const auto plan = procedures::make_plan(procedures::load_procedure("six-position"), station);
  const auto coverage = plan_coverage(
      plan, station,
      solver::Model::parse("accel_bias,accel_scale,accel_misalignment,gyro_bias,gyro_scale,"
                           "earth_rate"));
  for (const auto& u : coverage.units) {
    EXPECT_TRUE(undetermined_of(u, "accel").empty()) << u.imu;
    EXPECT_EQ(undetermined_of(u, "gyro_scale").size(), 3u) << u.imu;
  }
  const nlohmann::json j = to_json(coverage);
  EXPECT_EQ(j["units"].size(), 2u);
  EXPECT_EQ(j["units"][1]["imu"], "imu1");
}

// The steps recorded while the chamber ramps are points at their own temperatures: two ramps
// with rotations determine bias curves of order 3 and the temperature scale terms, which the
// same steps all put at the ramp's target would not (one temperature each way: order 1 at
// most), and a staircase of two plateaus determines order 1 only.
TEST(PlanCoverage, StepsRecordedDuringARampArePointsAtTheirOwnTemperatures) {
  const core::StationConfig station = sim::default_station();
  const solver::Model model = solver::Model::parse(
      "gyro_bias,gyro_scale,gyro_misalignment,earth_rate,accel_bias,accel_scale,"
      "accel_misalignment,gyro_temp_bias:3,accel_temp_bias:3,gyro_temp_scale,accel_temp_scale");
  const auto ramp = plan_coverage(
      procedures::make_plan(procedures::load_procedure("thermal-ramp"), station,
                            procedures::parse_overrides({"low_c=15", "high_c=35", "cycles=5"})),
      station, model);
  ASSERT_EQ(ramp.units.size(), 1u);
  EXPECT_TRUE(ramp.units[0].undetermined.empty());
  const auto staircase = plan_coverage(
      procedures::make_plan(procedures::load_procedure("thermal-calibration"), station,
                            procedures::parse_overrides({"temperatures=[15,35]"})),
      station, model);
  EXPECT_EQ(undetermined_of(staircase.units[0], "gyro_temp_bias"),
            (std::set<std::string>{"gyro_temp_bias.x2", "gyro_temp_bias.y2", "gyro_temp_bias.z2",
                                   "gyro_temp_bias.x3", "gyro_temp_bias.y3", "gyro_temp_bias.z3"}));
}

}  // namespace
}  // namespace calstand::analysis
