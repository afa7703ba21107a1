#include "core/table_geometry.hpp"

#include <gtest/gtest.h>

#include "core/rotation.hpp"

namespace calstand::core {
namespace {

// Default table: outer axis horizontal pointing North, inner axis normal to the table top
// (Up at outer = 0). Specific force at rest in L is (0, 0, g); in B it is C_BL f_L, so the body
// axis that points up reads +g.
Eigen::Vector3d force_in_body(const TableGeometry& t, double outer, double inner) {
  return t.body_to_level(outer, inner).transpose() * Eigen::Vector3d(0.0, 0.0, 1.0);
}

void expect_vec(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double tol = 1e-12) {
  EXPECT_NEAR((a - b).norm(), 0.0, tol) << "got " << a.transpose() << " want " << b.transpose();
}

TEST(TableGeometry, EachBodyAxisUpOrDownFromHandWorkedAngles) {
  const TableGeometry t;
  // outer 0: table top level, body z up.
  expect_vec(force_in_body(t, 0, 0), {0, 0, 1});
  // outer 180: table upside down, body z down.
  expect_vec(force_in_body(t, 180, 0), {0, 0, -1});
  // Outer about North by +90 deg: right-handed, the platform z axis (was Up) goes to -East...
  // R(N, 90) maps Up (0,0,1) to (1,0,0) = East? Rotation about y by +90: z -> x. So body z
  // points East (horizontal) and body x, which was East, now points Down: body x reads -1.
  expect_vec(force_in_body(t, 90, 0), {-1, 0, 0});
  expect_vec(force_in_body(t, -90, 0), {1, 0, 0});
  // Inner +90 first turns body x to North, then outer 90 about North leaves it North; body y
  // was -East... C_LB e_y = R(N,90) R(U,90) e_y = R(N,90) (-1,0,0) = (0,0,1): body y up.
  expect_vec(force_in_body(t, 90, 90), {0, 1, 0});
  expect_vec(force_in_body(t, 90, -90), {0, -1, 0});
}

TEST(TableGeometry, MountRotationIsAppliedLast) {
  TableGeometry t;
  t.mount_C_PB = from_roll_pitch_yaw_deg({180.0, 0.0, 0.0});  // IMU mounted upside down
  expect_vec(force_in_body(t, 0, 0), {0, 0, -1});
  EXPECT_TRUE(is_rotation(t.body_to_level(37.0, -123.0)));
}

TEST(TableGeometry, TableRateCarriesTheInnerAxis) {
  const TableGeometry t;
  // Inner axis at outer 0 is Up; at outer 90 about North it points East.
  expect_vec(t.table_rate_level_dps(0.0, 0.0, 10.0), {0, 0, 10});
  expect_vec(t.table_rate_level_dps(90.0, 0.0, 10.0), {10, 0, 0});
  expect_vec(t.table_rate_level_dps(90.0, 5.0, 10.0), {10, 5, 0});
}

TEST(TableGeometry, TableAccelerationMatchesNumericalDerivative) {
  const TableGeometry t;
  // Outer turning at 20 deg/s while accelerating at 3 deg/s^2; inner at -15 deg/s and 7 deg/s^2.
  const double outer0 = 31.0, w_o = 20.0, a_o = 3.0, w_i = -15.0, a_i = 7.0;
  const double h = 1e-5;
  auto rate_at = [&](double dt) {
    const double outer = outer0 + w_o * dt + 0.5 * a_o * dt * dt;
    return t.table_rate_level_dps(outer, w_o + a_o * dt, w_i + a_i * dt);
  };
  const Eigen::Vector3d numeric = (rate_at(h) - rate_at(-h)) / (2 * h);
  expect_vec(t.table_accel_level_dps2(outer0, w_o, w_i, a_o, a_i), numeric, 1e-6);
}

TEST(Rotation, AxisAngleIsRightHanded) {
  // +90 deg about Up turns East into North.
  expect_vec(axis_angle({0, 0, 1}, kPi / 2) * Eigen::Vector3d(1, 0, 0), {0, 1, 0});
  expect_vec(skew({1, 2, 3}) * Eigen::Vector3d(4, 5, 6),
             Eigen::Vector3d(1, 2, 3).cross(Eigen::Vector3d(4, 5, 6)));
  // Yaw 90 maps body x (forward) onto L's y.
  expect_vec(from_roll_pitch_yaw_deg({0, 0, 90}) * Eigen::Vector3d(1, 0, 0), {0, 1, 0});
}

}  // namespace
}  // namespace calstand::core
