#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "store/database.hpp"

namespace calstand::store {

/// One fit of a run as the history keeps it.
struct FitRecord {
  std::int64_t id = 0;  ///< set by the store
  std::int64_t run = 0;
  std::string device;
  std::string command;                    ///< "fit", "diagnose", "calibrate", "report"
  std::string model;                      ///< the --model text
  std::vector<std::string> custom_terms;  ///< NAME=SENSOR:EXPR
  std::string sensors;                    ///< both, gyro or accel
  int parameters = 0;                     ///< identified parameters
  std::optional<double> chi2_dof;
  std::optional<double> rms_gyro_dps;    ///< step-mean residual rms
  std::optional<double> rms_accel_mps2;  ///< or |f| - g rms (runs without a table)
  /// Runs without a table: rms of the gravity direction after each turn [deg].
  std::optional<double> rms_turn_deg;
  std::string created_utc;  ///< set by the store when empty
};

/// Appends a fit to the history; returns its id. Throws core::InputError for an unknown run.
std::int64_t record_fit(Database& db, const FitRecord& fit);

/// The fits of `run`, oldest first.
std::vector<FitRecord> fit_history(Database& db, std::int64_t run);

}  // namespace calstand::store
