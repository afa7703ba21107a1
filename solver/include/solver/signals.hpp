#pragma once

#include <Eigen/Core>
#include <array>
#include <string_view>
#include <vector>

#include "core/imu_sample.hpp"
#include "solver/run_setup.hpp"
#include "store/step_data.hpp"

namespace calstand::solver {

/// The signals of error-model.md at one sample, plus the geometry the reference terms need.
/// Everything is in the body frame B.
struct Signals {
  double temperature_c = 0.0;                                ///< IMU temperature [degC]
  double dT_c = 0.0;                                         ///< temperature - T_ref [degC]
  double temperature_rate_cpm = 0.0;                         ///< dT/dt [degC/min]
  double elapsed_s = 0.0;                                    ///< since the run's first sample [s]
  Eigen::Vector3d rate_dps = Eigen::Vector3d::Zero();        ///< reference w [deg/s]
  Eigen::Vector3d table_rate_dps = Eigen::Vector3d::Zero();  ///< table part of w [deg/s]
  /// Angular acceleration of the table [deg/s^2]: non-zero at constant axis rates when both
  /// axes turn, because the outer axis carries the inner one.
  Eigen::Vector3d table_accel_dps2 = Eigen::Vector3d::Zero();
  Eigen::Vector3d force_mps2 = Eigen::Vector3d::Zero();      ///< reference f, level table [m/s^2]
  Eigen::Vector3d earth_rate_dps = Eigen::Vector3d::Zero();  ///< Earth rate in B [deg/s]
  Eigen::Matrix3d C_BL = Eigen::Matrix3d::Identity();        ///< level frame to body
};

/// Names of the scalar signals custom expressions and residual correlation use, in the order
/// signal_values() returns them: temperature, temperature_rate, elapsed, rate_x..z,
/// force_x..z, table_rate_x..z.
const std::vector<std::string_view>& signal_names();
inline constexpr std::size_t kSignalCount = 12;
std::array<double, kSignalCount> signal_values(const Signals& s);

/// Computes the signals of a run's samples from the table state, following error-model.md:
/// w = C_BL (w_table_L [+ w_ie_L]), f = C_BL f_L. Earth rate enters `rate_dps` only when the
/// model holds the term `earth_rate` (`with_earth_rate`).
class SignalBuilder {
 public:
  SignalBuilder(const RunSetup& setup, bool with_earth_rate);

  /// Signals of one sample. `temperature_rate_cpm` and `elapsed_s` come from the caller
  /// (step_temperature_rates() and the run's first sample time).
  Signals operator()(const core::ImuSample& sample, const store::TableSample& table,
                     double temperature_rate_cpm, double elapsed_s) const;

  /// The same for a known body rate and force (correction of raw data, where the true rate
  /// and force are estimated from the measurement itself): `rate_dps` is the full w (Earth
  /// included), `table` still gives the table part and the attitude.
  Signals with_inputs(const Eigen::Vector3d& rate_dps, const Eigen::Vector3d& force_mps2,
                      const store::TableSample& table, double temperature_c,
                      double temperature_rate_cpm, double elapsed_s) const;

  /// Moves `signals`, built for the previous sample, on to `sample` at the same table state:
  /// the same as operator() (the rotations, rates and forces kept, the temperature and time of
  /// this sample), without the trigonometry. The samples of a static step share one state;
  /// updated in place, a long run's samples are not copied twice more.
  void advance_at_same_table(Signals& signals, const core::ImuSample& sample,
                             double temperature_rate_cpm, double elapsed_s) const;

  double temperature_ref_c() const { return temperature_ref_c_; }

 private:
  core::TableGeometry geometry_;
  Eigen::Vector3d force_level_mps2_;
  Eigen::Vector3d earth_level_dps_;
  double temperature_ref_c_;
  bool with_earth_rate_;
  /// The outer axis normalised, and whether normalising it again changes it (then the table's
  /// angular acceleration turns about that one, as TableGeometry computes it).
  Eigen::Vector3d outer_unit_;
  bool outer_unit_renormalises_ = false;
};

/// dT/dt at each sample of a step [degC/min]: the least-squares slope of the IMU temperature
/// over a window of +-`half_window_s` around the sample, clipped to the step (a derivative of
/// raw samples would be all quantization noise). Empty input gives an empty result.
std::vector<double> step_temperature_rates(const std::vector<core::ImuSample>& samples,
                                           double half_window_s = 30.0);

}  // namespace calstand::solver
