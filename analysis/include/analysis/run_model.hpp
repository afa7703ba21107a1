#pragma once
// What every fit of a run starts from: the model (catalogue terms and custom terms), the rows
// to fit, and the run's data with errors that say whether the run is missing or has nothing to
// fit. Shared by `calstand fit|diagnose|calibrate|report` and the daemon's /runs/{id}/fits.

#include <cstdint>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "solver/fit.hpp"
#include "solver/model.hpp"
#include "solver/step_summary.hpp"
#include "store/database.hpp"

namespace calstand::analysis {

/// The model `fit` and `calibrate` use when none is given: the classical bias, scale factor and
/// misalignment of both triads, with the Earth rate in the reference.
inline constexpr const char* kDefaultModel =
    "gyro_bias,gyro_scale,gyro_misalignment,earth_rate,accel_bias,accel_scale,accel_misalignment";

/// "both", "gyro" or "accel" as the rows of a fit. Throws core::InputError naming `where`
/// for anything else.
solver::SensorRows parse_sensor_rows(const std::string& sensor,
                                     const std::string& where = "--sensor");

/// A model given as lists, as a JSON request gives it: `terms` of the catalogue
/// ("gyro_temp_bias:2"), `customs` as NAME=SENSOR[.AXES]:EXPR. An empty `terms` is the default
/// model. Throws core::InputError naming the entry at fault ("model[2]", "custom[0]") and why:
/// an unknown term, a bad order, a custom expression that does not compile, a name twice.
solver::Model model_from_lists(const std::vector<std::string>& terms,
                               const std::vector<std::string>& customs);

/// The run is not in the database (HTTP 404).
class RunNotFound : public core::InputError {
 public:
  using core::InputError::InputError;
};

/// The run exists but holds no completed step with samples (yet): nothing to fit (HTTP 409).
class NothingToFit : public core::InputError {
 public:
  using core::InputError::InputError;
};

/// The checks every analysis makes of a run, whatever its device: an unknown run throws
/// RunNotFound, a run without samples NothingToFit.
void require_fit_run(store::Database& db, std::int64_t run);

/// The device of `run` to analyse (`device`, or "" for the run's only IMU), after the checks
/// every analysis makes: an unknown run throws RunNotFound, a run without samples NothingToFit,
/// an unknown or ambiguous device core::InputError (store::choose_device()).
std::string choose_fit_device(store::Database& db, std::int64_t run, const std::string& device);

/// The data of `run` for `device` ("" = the run's only IMU), as solver::load_run_data() with
/// the same messages, but an unknown run throws RunNotFound and a run without samples or
/// completed steps NothingToFit; an unknown or ambiguous device stays a core::InputError.
solver::RunData load_fit_data(store::Database& db, std::int64_t run, const std::string& device);

}  // namespace calstand::analysis
