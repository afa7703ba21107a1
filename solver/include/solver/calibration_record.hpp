#pragma once

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/version.hpp"
#include "solver/fit.hpp"
#include "solver/run_setup.hpp"
#include "store/step_data.hpp"

namespace calstand::solver {

inline constexpr const char* kCalibrationFormat = "calstand-calibration/1";
inline constexpr const char* kSoftwareVersion = "calstand " CALSTAND_VERSION;

/// Builds a calibration record (schemas/calibration.schema.json) from a fit of `model` on the
/// run of `setup`; `noise` (per-channel noise figures, or null) is stored as given. The valid
/// temperature range is the range of the steps' mean temperatures.
nlohmann::json make_calibration_record(const RunSetup& setup, const Model& model,
                                       const FitResult& fit, const std::vector<StepSummary>& steps,
                                       const nlohmann::json& noise = nullptr);

/// A calibration record ready to apply: its model and the value of each model parameter (zero
/// for those the record lists as not determined).
struct Calibration {
  nlohmann::json record;
  Model model;
  Eigen::VectorXd values;
  double temperature_ref_c = 25.0;
  double valid_min_c = 0.0;
  double valid_max_c = 0.0;
};

/// Reads a record: schema check (every violation listed), then the model and parameter names
/// against the catalogue. Throws core::InputError naming `file_name` and the field.
Calibration read_calibration(const nlohmann::json& record, const std::string& file_name);

/// Corrects raw samples with a calibration: the inverse of the measurement model. Given the
/// measured (gyro, accel), finds the rate and force whose modelled measurement equals it, by
/// fixed-point iteration (the sensor terms are small, so it converges in a few steps). Only
/// sensor terms are removed: the Earth rate and the table tilt are not errors of the IMU.
class Corrector {
 public:
  Corrector(const Calibration& calibration, const RunSetup& setup);
  /// Corrects every sample of `step` in place; `run_start_s` is the run's first sample time.
  void correct(store::StepData& step, double run_start_s) const;

 private:
  Model model_;
  Eigen::VectorXd values_;
  SignalBuilder build_;
};

}  // namespace calstand::solver
