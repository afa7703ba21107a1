// Contract names (../shared/docs/error-model.md) for the matrix-form results.

#include <array>

#include "solver/classical.hpp"

namespace calstand::solver {

std::vector<ClassicalEstimate> named_parameters(const MatrixCalibration& fit,
                                                ClassicalSensor sensor) {
  const bool gyro = sensor == ClassicalSensor::kGyro;
  const std::string prefix = gyro ? "gyro_" : "accel_";
  const std::string unit = gyro ? "deg/s" : "m/s^2";
  constexpr std::array<char, 3> kAxis{'x', 'y', 'z'};
  std::vector<ClassicalEstimate> out;
  for (int i = 0; i < 3; ++i) {
    out.push_back({prefix + "bias." + kAxis[i], fit.bias(i), fit.bias_sigma(i), unit});
  }
  for (int i = 0; i < 3; ++i) {
    out.push_back({prefix + "scale." + kAxis[i], fit.scale_ppm(i), fit.scale_sigma_ppm(i), "ppm"});
  }
  // Contract order .xy .xz .yx .yz .zx .zy: M[i][j] couples reference axis j into axis i.
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      if (i == j) continue;
      out.push_back({prefix + "misalignment." + kAxis[i] + kAxis[j], fit.misalignment_rad(i, j),
                     fit.misalignment_sigma_rad(i, j), "rad"});
    }
  }
  return out;
}

}  // namespace calstand::solver
