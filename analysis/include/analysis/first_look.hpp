#pragma once
// What a first look at an IMU measured (the library procedure `first-look`, which `calstand demo`
// runs): the classic hand calculations of the seed notes on a recorded run, before any fit.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "store/database.hpp"

namespace calstand::analysis {

/// The means of one static capture with a body axis pointed up or down.
struct PositionMean {
  std::size_t step = 0;  ///< step index of the capture
  std::string label;     ///< the capture's label, e.g. "x up"
  int axis = 0;          ///< body axis along the vertical: 0, 1, 2 for x, y, z
  int sign = +1;         ///< +1: pointed up (reads +g), -1: down
  double outer_deg = 0.0;
  double inner_deg = 0.0;
  Eigen::Vector3d gyro_dps = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_mps2 = Eigen::Vector3d::Zero();
  double temperature_c = 0.0;
  std::size_t samples = 0;
};

/// One accelerometer by the two-position method: bias = (up + down) / 2 and
/// scale = (up - down) / 2g - 1, from its axis up and down.
struct TwoPositionAccel {
  int axis = 0;
  std::size_t up = 0;    ///< index into FirstLook::positions
  std::size_t down = 0;  ///< index into FirstLook::positions
  double bias_mps2 = 0.0;
  double scale_ppm = 0.0;
};

/// One constant-rate capture of the rate test.
struct RateCapture {
  std::size_t step = 0;
  std::string label;
  double rate_dps = 0.0;       ///< commanded table rate, signed about the table axis
  double gyro_dps = 0.0;       ///< mean of the body axis along the turning table axis
  double reference_dps = 0.0;  ///< table rate plus the Earth rate, along that body axis
  std::size_t samples = 0;
};

/// A CW/CCW pair about one table axis over whole revolutions: the Earth rate across the axis
/// and the gyro's bias average out of each mean; the difference of the two means leaves the
/// scale factor, their sum the bias plus the Earth rate along the axis.
struct RateTest {
  std::string table_axis;  ///< "outer" or "inner"
  int body_axis = 2;       ///< the body axis most nearly along it
  int direction = +1;      ///< +1 when that body axis points along the table axis, else -1
  double outer_deg = 0.0;  ///< table angles during the test (the turning one at its start)
  double inner_deg = 0.0;
  RateCapture positive;
  RateCapture negative;
  double scale_ppm = 0.0;
  double bias_dps = 0.0;  ///< after the Earth rate along the axis is removed
};

/// A mark of a chamber step: the air and the IMU's own temperature some minutes after the
/// setpoint changed.
struct ThermalMark {
  std::size_t step = 0;
  double t_min = 0.0;  ///< since the set_temperature step started [min]
  double air_c = 0.0;  ///< chamber telemetry at the capture's start [degC]
  double imu_c = 0.0;  ///< the capture's mean IMU temperature [degC]
  double setpoint_c = 0.0;
  /// Mean IMU temperature rate since the previous mark [degC/min]; NaN at the first.
  double imu_rate_c_per_min = 0.0;
};

/// Everything first_look() found in a run.
struct FirstLook {
  std::int64_t run = 0;
  std::string device;
  double gravity_mps2 = 0.0;
  double latitude_deg = 0.0;
  Eigen::Vector3d earth_rate_level_dph = Eigen::Vector3d::Zero();  ///< E, N, U [deg/h]
  std::vector<PositionMean> positions;                             ///< in step order
  std::vector<TwoPositionAccel> accel;  ///< axes with both an up and a down position
  std::optional<RateTest> rate_test;    ///< the first CW/CCW pair of equal |rate|
  std::vector<ThermalMark> thermal;     ///< captures after the last set_temperature step
  double station_time_s = 0.0;          ///< end of the last step [s]
};

/// Reads `run` (device "" = its only IMU) step by step and finds: every completed static capture
/// that follows a move given by pointing (`"up": "+x"`), the two-position accelerometer figures
/// where an axis was pointed both ways, the first pair of rate steps about one table axis with
/// opposite rates of equal size, and the captures after the run's last set_temperature step.
/// Throws RunNotFound, NothingToFit, or core::InputError (an ambiguous device, a snapshot
/// without site or table).
FirstLook first_look(store::Database& db, std::int64_t run, const std::string& device = "");

}  // namespace calstand::analysis
