#pragma once

#include <pqxx/connection>

#include "store/record_source.hpp"

namespace calstand::fleet {

/// The calibration records and verdicts of every station in the central database, for the
/// analyses that read a store::RecordSource (`calstand lot --from`, `trend --from`, `fleet
/// calibrations`). Calibration and acceptance ids are the central ones; a row's run is the
/// station's own run id, and the row names its station (its registered name).
/// Reads with the connection's role: a reader sees the fleet, a station role its own rows.
/// Throws CentralError. `connection` must outlive it; not thread safe.
class CentralRecords : public store::RecordSource {
 public:
  explicit CentralRecords(pqxx::connection& connection) : connection_(connection) {}
  std::vector<store::CalibrationRow> calibrations_since(const std::string& since_utc) override;
  std::vector<store::CalibrationRow> calibrations_of_serial(const std::string& serial) override;
  std::optional<store::AcceptanceRow> latest_acceptance(std::int64_t calibration) override;

 private:
  pqxx::connection& connection_;
};

}  // namespace calstand::fleet
