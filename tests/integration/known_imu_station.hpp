#pragma once
// A simulated station whose IMU has known errors and white noise only (no turn-on bias, no
// correlated noise), shared by the tests that check fits against the truth: a calibration from
// one run holds exactly for the next, and a fit's errors are pure noise.

#include <nlohmann/json.hpp>
#include <string>

namespace calstand::testing {

inline constexpr const char* kKnownImuParameters = R"({
  "gyro_bias.x": 0.002, "gyro_bias.y": -0.001, "gyro_bias.z": 0.003,
  "gyro_scale.x": 300, "gyro_scale.y": -200, "gyro_scale.z": 150,
  "gyro_misalignment.xy": 0.0005, "gyro_misalignment.zx": -0.0003,
  "accel_bias.x": 0.01, "accel_bias.y": -0.02, "accel_bias.z": 0.005,
  "accel_scale.x": -400, "accel_scale.y": 250, "accel_scale.z": 100,
  "accel_misalignment.yx": 0.0004, "accel_misalignment.xz": -0.0002})";

/// The true value of contract parameter `name` (0 for terms the IMU does not have).
inline double known_imu_truth(const std::string& name) {
  return nlohmann::json::parse(kKnownImuParameters).value(name, 0.0);
}

/// The station file text: seeded with `seed`, the IMU at `rate_hz`.
inline std::string known_imu_station(const std::string& name, int seed, int rate_hz = 200) {
  return std::string(R"({"format": "calstand-station/1", "name": ")") + name + R"(", "seed": )" +
         std::to_string(seed) + R"(,
      "site": {"latitude_deg": 30.5, "height_m": 25},
      "table": {"backend": "sim", "outer_axis": [0, 1, 0], "inner_axis": [0, 0, 1],
                "outer": {"max_rate_dps": 400, "max_accel_dps2": 300},
                "inner": {"max_rate_dps": 1000, "max_accel_dps2": 500}},
      "chamber": {"backend": "sim", "min_c": -55, "max_c": 125, "max_ramp_c_per_min": 5},
      "imus": [{"name": "imu0", "backend": "sim", "truth": {"format": "calstand-truth/1",
        "parameters": )" +
         kKnownImuParameters + R"(,
        "noise": {"gyro": {"arw_deg_per_sqrt_h": 0.1}, "accel": {"vrw_mps_per_sqrt_h": 0.03}},
        "output": {"sample_rate_hz": )" +
         std::to_string(rate_hz) + R"(}}}]})";
}

}  // namespace calstand::testing
