#pragma once
// Thermal hysteresis (`calstand analyze hysteresis`): the calibration parameters at each set
// point of a temperature staircase, fitted on the way up and on the way down, and their
// difference beside its uncertainty.

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "store/database.hpp"

namespace calstand::analysis {

/// The model fitted at each set point and leg: what six static positions determine.
inline constexpr const char* kHysteresisModel = "gyro_bias,earth_rate,accel_bias,accel_scale";

/// One parameter at one set point: its value on each leg and the difference.
struct HysteresisPoint {
  double temperature_c = 0.0;  ///< the set point
  std::string parameter;
  std::string unit;
  double up = 0.0;
  double up_sigma = 0.0;
  double down = 0.0;
  double down_sigma = 0.0;
  double difference = 0.0;  ///< up - down
  double difference_sigma = 0.0;
  double z = 0.0;  ///< difference / its sigma: beyond about 4, hysteresis
};

struct HysteresisAnalysis {
  std::int64_t run = 0;
  std::string device;
  std::string model;
  /// Set points fitted on both legs, each parameter's row, by temperature then model order.
  std::vector<HysteresisPoint> points;
  std::vector<double> up_only_c;    ///< set points only on the way up (the top)
  std::vector<double> down_only_c;  ///< ... only on the way down
};

/// Groups the run's completed steps by their `leg` ("up"/"down") and `temperature` loop values
/// (library procedure thermal-hysteresis) and fits kHysteresisModel on each group with the
/// run's own noise model. Throws core::InputError naming the run when no set point has both
/// legs.
HysteresisAnalysis analyse_hysteresis(store::Database& db, std::int64_t run,
                                      const std::string& device);

/// `{"run", "device", "model", "points": [{"temperature_c", "parameter", "unit", "up",
///   "up_sigma", "down", "down_sigma", "difference", "difference_sigma", "z"}],
///   "up_only_c", "down_only_c"}`
nlohmann::json to_json(const HysteresisAnalysis& h);

}  // namespace calstand::analysis
