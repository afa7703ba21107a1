#pragma once

#include <Eigen/Core>
#include <cstdint>

namespace calstand::core {

/// One output sample of an IMU, as a driver delivers it.
///
/// Two time stamps: the device's own clock (what the sensor claims, may drift and wrap in real
/// hardware) and the station clock at reception (what the engine orders samples by).
struct ImuSample {
  double device_time_s = 0.0;   ///< IMU clock at the sample instant [s]
  double receive_time_s = 0.0;  ///< station clock when the sample arrived [s]
  std::uint32_t sequence = 0;   ///< device sequence counter; wraps at the device's modulus
  Eigen::Vector3d gyro_dps = Eigen::Vector3d::Zero();    ///< angular rate, body frame [deg/s]
  Eigen::Vector3d accel_mps2 = Eigen::Vector3d::Zero();  ///< specific force, body frame [m/s^2]
  double temperature_c = 0.0;                            ///< sensor's internal temperature [degC]
};

}  // namespace calstand::core
