#pragma once
// A unit's calibration certificate (`calstand certificate`): one A4 page per unit saying who
// was calibrated, where, by which procedure, with what result and expanded uncertainty, against
// which specification, and how the station's own equipment stood.

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "solver/fit.hpp"
#include "store/acceptances.hpp"
#include "store/database.hpp"

namespace calstand::analysis {

/// Coverage factor of the expanded uncertainties a certificate states (U = k sigma, about 95 %).
inline constexpr double kCertificateCoverageFactor = 2.0;

/// One piece of the station's equipment and whether its calibration covered the run.
struct EquipmentStatus {
  std::string name;
  std::string id;
  std::string calibrated;   ///< YYYY-MM-DD, or empty
  std::string due;          ///< YYYY-MM-DD
  std::string certificate;  ///< its own certificate's number, or empty
  bool overdue = false;     ///< its calibration had expired when the run ended
};

/// Everything one certificate states, read from the database.
struct CertificateData {
  std::string number;  ///< unique: station name and calibration id (the same on every render)
  std::string issued_utc;
  std::int64_t calibration = 0;
  std::int64_t run = 0;
  nlohmann::json record;  ///< the calibration record (schemas/calibration.schema.json)
  std::string device;     ///< the slot at the station
  std::string model;
  std::string serial;
  std::string station;
  nlohmann::json site;  ///< latitude_deg, longitude_deg, height_m (gravity_mps2) of the run
  std::vector<EquipmentStatus> equipment;
  std::string procedure;
  std::string procedure_sha256;
  std::string run_started_utc;
  std::string run_ended_utc;
  std::optional<store::AcceptanceRow> acceptance;  ///< the latest judgement; none: not judged
  /// The step residuals of the fit that made the record, for the residual plot: as stored with
  /// it (analysis/step_residuals.hpp); for a record stored without them (made before schema
  /// version 7), the record's model fitted again to the run. None for a calibration without a
  /// table.
  std::optional<std::vector<solver::StepResidual>> residuals;
  /// The residuals came from a refit, not from the record: for the tests and logs, never shown
  /// on the certificate (the customer's page is the same either way).
  bool residuals_refitted = false;
};

/// The newest calibration of `device` fitted on `run`. Throws core::InputError naming the run
/// when it has none (calibrate it first), or when `device` is empty and the run has records of
/// several units.
std::int64_t calibration_of_unit(store::Database& db, std::int64_t run, const std::string& device);

/// Reads calibration `calibration` and all its certificate states. Throws core::InputError for
/// an unknown calibration.
CertificateData certificate_data(store::Database& db, std::int64_t calibration);

/// Residual z-scores of the record's fit per step (gyro and accelerometer panels, +-2 band) as
/// inline SVG, sized for the certificate's page. Throws core::InputError naming gnuplot when it
/// is missing or fails.
std::string certificate_residual_plot(const std::vector<solver::StepResidual>& steps);

/// The certificate as a self-contained HTML page (A4, printable on one page).
std::string certificate_html(const CertificateData& data);

}  // namespace calstand::analysis
