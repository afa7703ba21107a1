#include "core/table_geometry.hpp"

#include "core/rotation.hpp"

namespace calstand::core {

Eigen::Matrix3d TableGeometry::body_to_level(double outer_deg, double inner_deg) const {
  return axis_angle(outer_axis, outer_deg * kDegToRad) *
         axis_angle(inner_axis, inner_deg * kDegToRad) * mount_C_PB;
}

Eigen::Vector3d TableGeometry::table_rate_level_dps(double outer_deg, double outer_rate_dps,
                                                    double inner_rate_dps) const {
  const Eigen::Vector3d inner_now =
      axis_angle(outer_axis, outer_deg * kDegToRad) * inner_axis.normalized();
  return outer_rate_dps * outer_axis.normalized() + inner_rate_dps * inner_now;
}

Eigen::Vector3d TableGeometry::table_accel_level_dps2(double outer_deg, double outer_rate_dps,
                                                      double inner_rate_dps,
                                                      double outer_accel_dps2,
                                                      double inner_accel_dps2) const {
  const Eigen::Vector3d a_o = outer_axis.normalized();
  const Eigen::Vector3d inner_now =
      axis_angle(a_o, outer_deg * kDegToRad) * inner_axis.normalized();
  // d/dt of (R(a_o, outer) a_i) is (outer_rate a_o) x (R a_i); the rate is in deg/s, so the
  // cross term needs one factor converted to rad/s to stay in deg/s^2.
  const Eigen::Vector3d carried = (outer_rate_dps * kDegToRad * a_o).cross(inner_now);
  return outer_accel_dps2 * a_o + inner_accel_dps2 * inner_now + inner_rate_dps * carried;
}

}  // namespace calstand::core
