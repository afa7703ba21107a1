#include "core/rotation.hpp"

#include <cmath>

namespace calstand::core {

Eigen::Matrix3d axis_angle(const Eigen::Vector3d& axis, double angle_rad) {
  return Eigen::AngleAxisd(angle_rad, axis.normalized()).toRotationMatrix();
}

Eigen::Matrix3d skew(const Eigen::Vector3d& a) {
  Eigen::Matrix3d m;
  m << 0.0, -a.z(), a.y(),  //
      a.z(), 0.0, -a.x(),   //
      -a.y(), a.x(), 0.0;
  return m;
}

Eigen::Matrix3d from_roll_pitch_yaw_deg(const Eigen::Vector3d& rpy_deg) {
  const Eigen::Vector3d r = rpy_deg * kDegToRad;
  return (Eigen::AngleAxisd(r.z(), Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(r.y(), Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(r.x(), Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

bool is_rotation(const Eigen::Matrix3d& m, double tol) {
  return (m * m.transpose() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() < tol &&
         std::abs(m.determinant() - 1.0) < tol;
}

}  // namespace calstand::core
