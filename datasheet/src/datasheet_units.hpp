#pragma once
// The datasheet units the analyses report in, one definition for the files of datasheet/ (a
// unity build compiles them as one file): gyro biases in deg/h, accelerometer biases in ug.

namespace calstand::analysis {

inline constexpr double kDegPerSToDegPerH = 3600.0;
inline constexpr double kMps2ToUg = 1e6 / 9.80665;  ///< per g0, as datasheets count g

}  // namespace calstand::analysis
