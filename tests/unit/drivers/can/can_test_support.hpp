#pragma once

#include <chrono>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "core/imu_sample.hpp"
#include "drivers/can_signal_map.hpp"
#include "drivers/imu.hpp"

namespace calstand::drivers::can_test {

/// The shipped example map (sim/can/calstand-imu-can.json).
inline std::string example_map_path() {
  return std::string(CALSTAND_SOURCE_DIR) + "/sim/can/calstand-imu-can.json";
}

inline CanSignalMap example_map() { return CanSignalMap::load(example_map_path(), "example"); }

/// A small valid map document to break one field at a time: two frames, float32 values.
inline nlohmann::json float_map_json() {
  return nlohmann::json::parse(R"({
    "signals": {
      "sequence":    {"start_byte": 0, "length_bits": 8},
      "gyro_x":      {"id": "0x201", "start_byte": 1, "length_bits": 32, "type": "float"},
      "gyro_y":      {"id": "0x202", "start_byte": 1, "length_bits": 32, "type": "float"},
      "gyro_z":      {"id": "0x203", "start_byte": 1, "length_bits": 32, "type": "float"},
      "accel_x":     {"id": "0x204", "start_byte": 1, "length_bits": 32, "type": "float"},
      "accel_y":     {"id": "0x205", "start_byte": 1, "length_bits": 32, "type": "float"},
      "accel_z":     {"id": "0x206", "start_byte": 1, "length_bits": 32, "type": "float"},
      "temperature": {"id": "0x201", "start_byte": 5, "length_bits": 16, "type": "signed",
                      "scale": 0.01, "unit": "degC"}
    }
  })");
}

/// A plausible sample: values that change with `sequence`, within the example map's ranges.
inline core::ImuSample sample(std::uint32_t sequence, double device_time_s) {
  core::ImuSample s;
  s.sequence = sequence;
  s.device_time_s = device_time_s;
  const double k = static_cast<double>(sequence);
  s.gyro_dps = {0.004178 + 1e-3 * k, -12.5 + 0.25 * k, 300.0 - k};
  s.accel_mps2 = {0.0123, -9.80665 + 1e-4 * k, 1.5 - 0.01 * k};
  s.temperature_c = 25.0 + 0.01 * k;
  return s;
}

/// Polls `imu` until `count` samples came or `timeout` passed.
inline std::vector<core::ImuSample> collect(
    Imu& imu, std::size_t count, std::chrono::milliseconds timeout = std::chrono::seconds(5)) {
  std::vector<core::ImuSample> got;
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (got.size() < count && std::chrono::steady_clock::now() < deadline) {
    auto more = imu.poll();
    got.insert(got.end(), more.begin(), more.end());
    if (more.empty()) std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  return got;
}

}  // namespace calstand::drivers::can_test
