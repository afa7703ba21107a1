#pragma once

#include <Eigen/Core>
#include <array>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "solver/model.hpp"
#include "solver/step_noise.hpp"
#include "solver/step_summary.hpp"

namespace calstand::solver {

/// Which sensors' rows a fit uses.
enum class SensorRows { kBoth, kGyro, kAccel };

struct FitOptions {
  SensorRows rows = SensorRows::kBoth;
  /// A parameter whose weighted regressor column lies within this sine of the span of the
  /// parameters before it is not determined by the run (exact collinearity up to rounding).
  double collinear_sine = 1e-6;
  /// ... and below this it is nearly so: its variance would be inflated by more than
  /// 1/sine^2 (1e6), i.e. it would be fitted to noise. Both are reported, neither fitted.
  double near_collinear_sine = 1e-3;
  /// Inflate the sigmas by sqrt(chi2/dof) when that exceeds 1 (the model misses something,
  /// so the noise floor alone understates the uncertainty). Gyro and accelerometer parameters
  /// are separate problems: each sensor's parameters are inflated by its own rows' chi2/dof.
  bool inflate_sigma_by_chi2 = true;
};

struct FittedParameter {
  std::string name;
  std::string unit;
  double value = 0.0;
  double sigma = 0.0;  ///< 1-sigma
};

/// A parameter the run cannot determine, and why.
struct Unidentifiable {
  std::string name;
  std::string reason;                ///< one sentence
  std::vector<std::string> related;  ///< parameters it is (nearly) collinear with
};

/// Step-mean residual (measured - model) of one step.
struct StepResidual {
  std::size_t index = 0;
  std::string label;
  double start_s = 0.0;  ///< first sample, since the run's first sample [s]
  double end_s = 0.0;    ///< last sample, since the run's first sample [s]
  bool is_static = false;
  std::array<double, kSignalCount> signals{};  ///< the step's mean of each signal (signal_names())
  Vector6d residual = Vector6d::Zero();        ///< [deg/s, m/s^2]
  /// The noise of this step's mean alone (white part and wander; neighbouring steps' noise is
  /// correlated with it when the noise model has a wander)
  Vector6d sigma = Vector6d::Zero();
  Vector6d z() const { return residual.cwiseQuotient(sigma); }
};

struct FitResult {
  std::string model;  ///< Model::text()
  std::vector<std::string> terms;
  std::vector<FittedParameter> parameters;  ///< identified ones, in model order
  std::vector<Unidentifiable> unidentifiable;
  Eigen::VectorXd values;      ///< every model parameter (0 for unidentifiable ones)
  Eigen::MatrixXd covariance;  ///< of `parameters`, in their order (sigma inflation applied)
  double chi2 = 0.0;           ///< against the noise model's covariance (whitened residuals)
  int dof = 0;
  double chi2_dof = 0.0;
  /// Per sensor: chi2/dof of the gyro rows and of the accelerometer rows, each against its own
  /// parameters (NaN when the sensor's rows are not fitted or leave no degree of freedom).
  double chi2_dof_gyro = 0.0;
  double chi2_dof_accel = 0.0;
  int dof_gyro = 0;
  int dof_accel = 0;
  double residual_rms_gyro_dps = 0.0;  ///< over step-mean residuals of all steps and axes
  double residual_rms_accel_mps2 = 0.0;
  Vector6d noise_floor = Vector6d::Zero();  ///< rms of the steps' mean sigmas, per channel
  NoiseFloor floor;                         ///< the white part, measured inside the steps
  StepNoise noise;                          ///< the whole noise model the weights came from
  double sample_rate_hz = 0.0;  ///< of the IMU, from the steps' sample counts and durations
  std::vector<StepResidual> steps;
  SensorRows rows = SensorRows::kBoth;
};

/// Generalised least squares of `model` on step summaries built for it: per channel, the step
/// means are whitened by the Cholesky factor of their covariance under `noise` (white noise
/// on the diagonal, a wandering bias between steps). Parameters the run cannot determine
/// (temperature orders at or above the number of distinct temperatures, columns collinear or
/// nearly collinear with earlier ones, columns with no excitation) are reported in
/// `unidentifiable` and held at zero. Throws core::InputError when there are fewer rows than
/// parameters.
FitResult fit_model(const std::vector<StepSummary>& steps, const Model& model,
                    const StepNoise& noise, const FitOptions& options = {});

/// The same with white noise only (weights from `floor`): the plain weighted least squares.
FitResult fit_model(const std::vector<StepSummary>& steps, const Model& model,
                    const NoiseFloor& floor, const FitOptions& options = {});

/// Step mean temperatures further apart than this [degC] are on different plateaus.
inline constexpr double kPlateauGapC = 2.0;

/// Temperature plateaus of a run: step mean temperatures clustered with gaps over kPlateauGapC.
/// A ramp recorded step after step is one plateau: consecutive steps are never that far apart.
std::vector<double> temperature_plateaus(const std::vector<StepSummary>& steps);

/// How many distinct temperatures a run's steps give a temperature polynomial: the step mean
/// temperatures in clusters no wider than kPlateauGapC, taken from the coldest up. A staircase
/// gives its plateaus; a ramp one per kPlateauGapC it covers (the ramp's steps are points of the
/// curve at their own temperatures, which a plateau count would merge into one).
std::size_t distinct_temperatures(const std::vector<StepSummary>& steps);

/// True when a chi-square of `chi2_dof` per degree of freedom over `dof` degrees is above what
/// the noise alone gives one time in a thousand: the model misses something (or the noise model
/// understates the noise). chi2/dof 1.3 over 1000 degrees is; 1.3 over 20 is not.
bool above_noise(double chi2_dof, int dof);

/// The fit as the `calstand fit --json` document.
nlohmann::json fit_to_json(const FitResult& fit);

}  // namespace calstand::solver
