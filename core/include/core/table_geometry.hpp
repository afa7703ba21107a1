#pragma once

#include <Eigen/Core>

namespace calstand::core {

/// Geometry of a dual-axis table and the IMU mount, in the frames of error-model.md.
///
/// L is the site's East-North-Up frame. `outer_axis` is fixed in L; `inner_axis` is given in L at
/// outer angle 0 and is carried by the outer axis. C_PB rotates the IMU body frame B into the
/// table platform frame P (identity unless the IMU is mounted rotated).
struct TableGeometry {
  Eigen::Vector3d outer_axis{0.0, 1.0, 0.0};  ///< unit vector in L (horizontal, North by default)
  Eigen::Vector3d inner_axis{0.0, 0.0, 1.0};  ///< unit vector in L at outer = 0 (Up by default)
  Eigen::Matrix3d mount_C_PB = Eigen::Matrix3d::Identity();

  /// C_LB = R(outer_axis, outer) * R(inner_axis, inner) * C_PB.
  Eigen::Matrix3d body_to_level(double outer_deg, double inner_deg) const;

  /// Table angular rate in L [deg/s]:
  /// outer_rate * outer_axis + inner_rate * R(outer_axis, outer) * inner_axis.
  Eigen::Vector3d table_rate_level_dps(double outer_deg, double outer_rate_dps,
                                       double inner_rate_dps) const;

  /// Time derivative of table_rate_level_dps in L [deg/s^2], from the axis accelerations.
  Eigen::Vector3d table_accel_level_dps2(double outer_deg, double outer_rate_dps,
                                         double inner_rate_dps, double outer_accel_dps2,
                                         double inner_accel_dps2) const;
};

}  // namespace calstand::core
