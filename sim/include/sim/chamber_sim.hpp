#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "core/chamber_state.hpp"
#include "sim/noise.hpp"
#include "sim/status.hpp"

namespace calstand::sim {

/// Thermal behaviour and limits of the simulated chamber and of the IMU inside it.
struct ChamberParams {
  double min_c = -60.0;                ///< lowest accepted setpoint [degC]
  double max_c = 150.0;                ///< highest accepted setpoint [degC]
  double max_ramp_c_per_min = 5.0;     ///< the air never changes faster than this [degC/min]
  double ambient_c = 23.0;             ///< lab air, where the chamber drifts in standby [degC]
  double air_time_constant_s = 90.0;   ///< first-order lag of the air behind the setpoint [s]
  double control_noise_c = 0.02;       ///< 1-sigma controller noise on the air [degC]
  double control_noise_tau_s = 20.0;   ///< correlation time of that noise [s]
  double imu_time_constant_s = 600.0;  ///< lag of the IMU's own temperature behind the air [s]
  double imu_self_heating_c = 3.0;     ///< IMU runs this much above the air when settled [degC]
};

/// The simulated temperature chamber (air temperature) and the IMU thermal mass in it.
///
/// The controller ramps its working setpoint linearly to the target at the requested rate
/// (capped at max_ramp_c_per_min); the air follows the working setpoint with a first-order lag
/// and never moves faster than max_ramp_c_per_min; a correlated controller noise rides on it.
/// The IMU temperature follows (air + self-heating) with its own, slower time constant; it
/// feels the controller noise too, since that is a real fluctuation of the air.
///
/// Power-up: standby, air and setpoint at ambient, and the IMU at ambient as well, just
/// switched on, so it warms up to ambient + self-heating over a few IMU time constants. While
/// the controller is idle (standby, fault) the working setpoint tracks the air, so a new
/// setpoint ramps from where the air is. Not thread safe; owned by the simulated world.
class ChamberSim {
 public:
  /// `seed` drives the controller noise only (derive it from the station seed).
  ChamberSim(ChamberParams params, std::uint64_t seed);

  /// Starts controlling to `target_c`, ramping at `ramp_c_per_min` (default and cap:
  /// max_ramp_c_per_min). Refused outside [min_c, max_c], for a non-positive ramp, or in fault.
  Status set_setpoint(double target_c, std::optional<double> ramp_c_per_min = std::nullopt);
  /// Stops controlling; the air drifts back to ambient (the safe state).
  void standby();
  /// A controller alarm: control stops (the air drifts to ambient), setpoints are refused
  /// until clear_fault(), which returns to standby.
  void inject_fault(std::string why);
  void clear_fault();

  /// Advances by dt_s > 0; any dt is modelled exactly (other values are ignored).
  void step(double dt_s);

  double air_temperature_c() const;                    ///< includes the controller noise [degC]
  double imu_temperature_c() const { return imu_c_; }  ///< [degC]
  /// Derivative of the IMU temperature at the end of the last step [degC/min].
  double imu_temperature_rate_c_per_min() const { return imu_rate_c_per_min_; }
  double working_setpoint_c() const { return working_setpoint_c_; }
  core::ChamberState state(double time_s) const;
  const ChamberParams& params() const { return params_; }

 private:
  /// Recomputes the per-step factors when dt_s differs from the last step's.
  void update_step_factors(double dt_s);

  ChamberParams params_;
  core::ChamberMode mode_ = core::ChamberMode::kStandby;
  double target_c_;            // last accepted setpoint (ambient at power-up) [degC]
  double ramp_c_per_min_;      // ramp in use, already capped at max_ramp_c_per_min
  double working_setpoint_c_;  // the controller's ramped setpoint; tracks the air when idle
  double air_c_;               // without noise [degC]
  double imu_c_;
  double imu_rate_c_per_min_ = 0.0;
  std::string fault_text_;
  // Controller noise as a Gauss-Markov process updated exactly for whatever dt step() gets
  // (sim::GaussMarkov fixes dt at construction).
  NormalSource normal_;
  double noise_c_ = 0.0;
  // exp() per step is avoided: the simulator steps at a fixed dt, so the factors are computed
  // once per distinct dt.
  double factors_dt_s_ = -1.0;
  double air_keep_ = 0.0;       // exp(-dt / air_time_constant_s)
  double imu_keep_ = 0.0;       // exp(-dt / imu_time_constant_s)
  double noise_keep_ = 0.0;     // exp(-dt / control_noise_tau_s)
  double noise_drive_c_ = 0.0;  // control_noise_c * sqrt(1 - noise_keep^2) [degC]
};

}  // namespace calstand::sim
