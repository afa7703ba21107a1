#pragma once

#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/station_config.hpp"
#include "procedures/procedure.hpp"

namespace calstand::procedures {

/// The longest plan accepted [s of station time]: a year. Longer is a mistake (a capture of
/// 1e308 s), and the run would never end.
inline constexpr double kMaxPlanDuration_s = 365.25 * 86400.0;

/// What one table axis is asked to do over a whole procedure.
struct AxisEnvelope {
  double max_rate_dps = 0.0;       ///< largest |rate| of its rate steps and oscillations [deg/s]
  double max_move_rate_dps = 0.0;  ///< largest peak |rate| of its moves [deg/s]
  double max_accel_dps2 = 0.0;     ///< acceleration used (the axis limit) if it moves at all
};

/// The ranges a procedure spans, to compare with a station at a glance.
struct Envelope {
  AxisEnvelope outer;
  AxisEnvelope inner;
  std::optional<double> min_temperature_c;  ///< lowest setpoint (absent: chamber untouched)
  std::optional<double> max_temperature_c;
  double max_ramp_c_per_min = 0.0;  ///< fastest ramp commanded [degC/min]
  double capture_s = 0.0;           ///< total recording time, captures and rates [s]
  std::size_t captures = 0;         ///< number of recording steps
  nlohmann::json to_json() const;
};

/// A procedure expanded and estimated against one station. Nothing runs.
///
/// Time estimates start with the table at rest at (0, 0) and the chamber at its ambient
/// temperature, and assume: moves follow a trapezoidal profile per axis at the axis rate and
/// acceleration limits, both axes at once, then the axis settle time; rate steps take
/// |change of rate| / accel, then settle_s, then the recording, then |rate| / accel to stop
/// when rest_after; an oscillation takes (settle_cycles + cycles) / frequency_hz and the axis
/// settle time (back at its start angle); a soaking set_temperature takes |change| / ramp + the
/// soak's stable_s (never the timeout). The chamber air and IMU thermal lags are NOT modelled: a
/// real soak usually takes longer than the estimate.
struct Plan {
  std::string procedure;  ///< the procedure's name
  std::string file_name;
  std::map<std::string, nlohmann::json> parameters;  ///< values used (defaults + overrides)
  std::vector<Step> steps;
  std::vector<double> step_start_s;     ///< estimated start of each step [s]
  std::vector<double> step_duration_s;  ///< estimated duration of each step [s]
  double total_s = 0.0;                 ///< estimated duration [s]
  Envelope envelope;
  /// Every rule broken: override and value rules of expansion, then station limits (rates
  /// above an axis limit, oscillations whose peak rate or acceleration is above it, setpoints
  /// outside the chamber range, ramps above its limit).
  std::vector<Violation> violations;

  bool ok() const { return violations.empty(); }
  nlohmann::json to_json() const;
};

/// Expands `procedure` with `overrides`, resolves every move given by pointing (`"up": "+x"`)
/// to table angles for the station's table and the IMU's mount (pointing.hpp), and estimates it
/// on `station`. Rule breaks go to Plan::violations (never thrown), so that one call lists them
/// all; a pointing the table cannot make is one, at the step's `up`.
Plan make_plan(const Procedure& procedure, const core::StationConfig& station,
               const Overrides& overrides = {});

/// Throws ProcedureError naming the plan's file and listing its violations unless plan.ok().
void require_valid(const Plan& plan);

/// Estimated time [s] of a rest-to-rest move of `distance_deg` (>= 0) on a trapezoidal
/// profile limited to `max_rate_dps` and `max_accel_dps2` (triangular when too short to reach
/// the rate limit). Settle time not included.
double trapezoid_move_s(double distance_deg, double max_rate_dps, double max_accel_dps2);

}  // namespace calstand::procedures
