#include "fleet/central_records.hpp"

#include <pqxx/pqxx>

#include "fleet/central_error.hpp"

namespace calstand::fleet {
namespace {

constexpr const char* kSelect =
    "SELECT c.id, r.local_id, c.imu, c.model, c.record::text, c.created_utc, c.serial, s.name "
    "FROM calibrations c JOIN stations s ON s.uuid = c.station JOIN runs r ON r.id = c.run_id ";

std::vector<store::CalibrationRow> rows_of(const pqxx::result& r) {
  std::vector<store::CalibrationRow> out;
  for (const auto& row : r) {
    store::CalibrationRow c;
    c.id = row[0].as<std::int64_t>();
    c.run = row[1].as<std::int64_t>();
    c.imu = row[2].as<std::string>();
    c.model = row[3].as<std::string>();
    c.record = nlohmann::json::parse(row[4].as<std::string>());
    c.created_utc = row[5].as<std::string>();
    c.serial = row[6].as<std::string>();
    c.station = row[7].as<std::string>();
    out.push_back(std::move(c));
  }
  return out;
}

}  // namespace

std::vector<store::CalibrationRow> CentralRecords::calibrations_since(
    const std::string& since_utc) {
  try {
    pqxx::read_transaction tx(connection_);
    return rows_of(tx.exec_params(
        std::string(kSelect) + "WHERE c.created_utc >= $1 ORDER BY c.created_utc, c.id",
        since_utc));
  } catch (...) {
    rethrow_as_central("read calibrations");
  }
}

std::vector<store::CalibrationRow> CentralRecords::calibrations_of_serial(
    const std::string& serial) {
  try {
    pqxx::read_transaction tx(connection_);
    return rows_of(tx.exec_params(
        std::string(kSelect) + "WHERE c.serial = $1 ORDER BY c.created_utc DESC, c.id DESC",
        serial));
  } catch (...) {
    rethrow_as_central("read calibrations");
  }
}

std::optional<store::AcceptanceRow> CentralRecords::latest_acceptance(std::int64_t calibration) {
  try {
    pqxx::read_transaction tx(connection_);
    const pqxx::result r = tx.exec_params(
        "SELECT id, calibration_id, spec_name, spec_sha256, verdict, result::text, created_utc "
        "FROM acceptances WHERE calibration_id = $1 ORDER BY created_utc DESC, id DESC LIMIT 1",
        calibration);
    if (r.empty()) return std::nullopt;
    return store::AcceptanceRow{
        r[0][0].as<std::int64_t>(), r[0][1].as<std::int64_t>(),
        r[0][2].as<std::string>(),  r[0][3].as<std::string>(),
        r[0][4].as<std::string>(),  nlohmann::json::parse(r[0][5].as<std::string>()),
        r[0][6].as<std::string>()};
  } catch (...) {
    rethrow_as_central("read acceptances");
  }
}

}  // namespace calstand::fleet
