#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace calstand::core {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegToRad = kPi / 180.0;
constexpr double kRadToDeg = 180.0 / kPi;

/// Right-handed rotation by `angle_rad` about the unit vector `axis` (normalised here).
/// Maps vectors expressed in the rotated frame into the reference frame.
Eigen::Matrix3d axis_angle(const Eigen::Vector3d& axis, double angle_rad);

/// Skew-symmetric cross-product matrix: skew(a) * b == a.cross(b).
Eigen::Matrix3d skew(const Eigen::Vector3d& a);

/// Direction cosine matrix C_AB of a body frame B relative to A from roll, pitch, yaw [deg]
/// (aerospace z-y-x sequence: C_AB = Rz(yaw) * Ry(pitch) * Rx(roll)).
Eigen::Matrix3d from_roll_pitch_yaw_deg(const Eigen::Vector3d& rpy_deg);

/// True when `m` is a rotation matrix to `tol` (orthonormal, determinant +1).
bool is_rotation(const Eigen::Matrix3d& m, double tol = 1e-9);

}  // namespace calstand::core
