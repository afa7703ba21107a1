#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "solver/model.hpp"
#include "solver/octave_allan.hpp"
#include "solver/run_setup.hpp"
#include "store/database.hpp"
#include "store/step_data.hpp"

namespace calstand::solver {

/// A run's data as the solver reads it once: the setup and every completed step's samples with
/// the table state per sample.
struct RunData {
  RunSetup setup;
  std::vector<store::StepData> steps;
};

/// Loads `run` for `device` ("" = the run's only IMU). Throws core::InputError for an unknown
/// run or device, or a run without completed steps.
RunData load_run_data(store::Database& db, std::int64_t run, const std::string& device = "");

/// One step reduced to what a fit needs: averages of the measurement, the reference and every
/// regressor over the step's samples (exact for terms linear in their parameters), the spread
/// of the step mean estimated inside the step, and the step's conditions for grouping.
struct StepSummary {
  std::size_t index = 0;  ///< step index in the run
  std::string label;
  std::int64_t count = 0;                 ///< samples
  double duration_s = 0.0;                ///< first to last sample [s]
  double start_s = 0.0;                   ///< first sample, since the run's first sample [s]
  double end_s = 0.0;                     ///< last sample, since the run's first sample [s]
  Vector6d measured = Vector6d::Zero();   ///< mean measurement [deg/s, m/s^2]
  Vector6d reference = Vector6d::Zero();  ///< mean reference (w, f) of the model
  Eigen::MatrixXd regressors;             ///< kChannels x parameters, step means
  /// Variance of the step mean per channel from inside the step (batch means: block means'
  /// Allan variance over the number of blocks, robust to a linear drift); NaN when the step is
  /// too short to tell.
  Vector6d mean_variance = Vector6d::Constant(std::numeric_limits<double>::quiet_NaN());
  /// Allan variance sums of measurement - reference at blocks of 1, 2, 4, ... samples, up to a
  /// tenth of the step: the curve the white noise floor is read from (octave_allan.hpp).
  std::vector<OctaveAllan> octave_allan;
  std::array<double, kSignalCount> signals{};      ///< mean of each signal (signal_names())
  std::array<double, kSignalCount> signals_sq{};   ///< mean of each signal squared
  std::array<double, kSignalCount> signals_abs{};  ///< mean of each signal's absolute value
  bool is_static = false;                          ///< the table was at rest
};

/// Summaries of every step of `data` for `model`, in step order.
std::vector<StepSummary> summarize_steps(const RunData& data, const Model& model);

/// The summaries of `subset` taken from summaries built for `superset` (regressor columns picked
/// by parameter name), so that many models can be fitted from one pass over the samples.
/// Throws std::invalid_argument when a parameter of `subset` is not in `superset` or the two
/// disagree on earth_rate (which changes the reference).
std::vector<StepSummary> select_parameters(const std::vector<StepSummary>& steps,
                                           const Model& superset, const Model& subset);

/// The measured noise floor: per channel, the white-equivalent variance of one sample such
/// that the step mean of n samples has variance density / n, pooled from the static steps
/// (all steps when the run has none).
struct NoiseFloor {
  Vector6d density = Vector6d::Zero();  ///< [unit^2] per channel
  /// The steps' scatter at a tenth of a step (batch means), per channel, in the same units: the
  /// white noise and the wander at that block length. The weights of a channel whose wander
  /// the run cannot estimate: a step mean moves by its wander too, and this figure holds at
  /// least the wander's part at a tenth of a step, where the white part holds none of it.
  Vector6d batch_density = Vector6d::Zero();
  std::size_t steps_used = 0;
  bool from_static_steps = true;
  /// Read from the steps' Allan curve (white part only); false: the batch means' figure at a
  /// tenth of a step, for runs whose steps are too short for three octaves.
  bool from_octave_fit = false;
  /// Expected standard deviation of a step mean of `count` samples, per channel.
  Vector6d step_sigma(std::int64_t count) const {
    return (density / static_cast<double>(count)).cwiseSqrt();
  }
};

/// The white noise of the steps' pooled Allan curve (white_variance_from_octaves), or where
/// the steps are too short for it, their own mean variances pooled. Throws core::InputError when no
/// step is long enough to measure its scatter.
NoiseFloor measure_noise_floor(const std::vector<StepSummary>& steps);

}  // namespace calstand::solver
