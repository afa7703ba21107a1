#include "fleet/fleet_queries.hpp"

#include <pqxx/pqxx>

#include "factory/lot.hpp"
#include "factory/unit_records.hpp"
#include "fleet/central_error.hpp"
#include "fleet/central_records.hpp"

namespace calstand::fleet {
namespace {

nlohmann::json text_or_null(const pqxx::field& f) {
  return f.is_null() ? nlohmann::json() : nlohmann::json(f.as<std::string>());
}

// The station filter matches the registered name or the uuid (as text: a name is not a uuid).
constexpr const char* kStationMatches = "($1 = '' OR s.name = $1 OR s.uuid::text = $1)";

}  // namespace

void FleetFilter::validate() const { analysis::check_lot_since(since_utc, "--since"); }

nlohmann::json fleet_stations(pqxx::connection& connection, const FleetFilter& filter) {
  filter.validate();
  try {
    pqxx::read_transaction tx(connection);
    const pqxx::result r = tx.exec_params(
        std::string("SELECT s.name, s.uuid::text, s.registered_utc, "
                    "(SELECT count(*) FROM runs r WHERE r.station = s.uuid), "
                    "last.created_utc, last.status, "
                    "(SELECT count(*) FROM calibrations c WHERE c.station = s.uuid), "
                    "(SELECT count(DISTINCT u.serial) FROM run_units u WHERE u.station = s.uuid "
                    "AND u.serial <> '') "
                    "FROM stations s LEFT JOIN LATERAL (SELECT r.created_utc, r.status FROM runs r "
                    "WHERE r.station = s.uuid ORDER BY r.created_utc DESC, r.id DESC LIMIT 1) last "
                    "ON true WHERE ") +
            kStationMatches + " ORDER BY s.name",
        filter.station);
    nlohmann::json stations = nlohmann::json::array();
    for (const auto& row : r) {
      stations.push_back({{"name", row[0].as<std::string>()},
                          {"uuid", row[1].as<std::string>()},
                          {"registered_utc", row[2].as<std::string>()},
                          {"runs", row[3].as<std::int64_t>()},
                          {"last_run_utc", text_or_null(row[4])},
                          {"last_run_status", text_or_null(row[5])},
                          {"calibrations", row[6].as<std::int64_t>()},
                          {"units", row[7].as<std::int64_t>()}});
    }
    return {{"stations", std::move(stations)}};
  } catch (...) {
    rethrow_as_central("read stations");
  }
}

nlohmann::json fleet_parameters(pqxx::connection& connection, const FleetFilter& filter) {
  filter.validate();
  try {
    pqxx::read_transaction tx(connection);
    // A unit counts once, with its newest record (as in a lot); records without a serial are
    // nobody's unit and are left out.
    const pqxx::result r = tx.exec_params(
        std::string("WITH newest AS (SELECT DISTINCT ON (c.serial) c.record, s.name AS station "
                    "FROM calibrations c JOIN stations s ON s.uuid = c.station WHERE c.serial <> "
                    "'' AND c.created_utc >= $3 AND ($2 = '' OR c.serial = $2) AND ") +
            kStationMatches +
            " ORDER BY c.serial, c.created_utc DESC, c.id DESC), "
            "p AS (SELECT station, e->>'name' AS name, e->>'unit' AS unit, "
            "(e->>'value')::double precision AS value FROM newest, "
            "jsonb_array_elements(newest.record->'parameters') e WHERE e ? 'value') "
            "SELECT name, max(unit), station, count(*), avg(value), stddev_samp(value), "
            "min(value), max(value) FROM p GROUP BY name, station ORDER BY name, station",
        filter.station, filter.serial, filter.since_utc);
    nlohmann::json parameters = nlohmann::json::array();
    for (const auto& row : r) {
      const std::string name = row[0].as<std::string>();
      if (parameters.empty() || parameters.back()["name"] != name) {
        parameters.push_back({{"name", name},
                              {"unit", row[1].is_null() ? "" : row[1].as<std::string>()},
                              {"stations", nlohmann::json::array()}});
      }
      parameters.back()["stations"].push_back(
          {{"station", row[2].as<std::string>()},
           {"n", row[3].as<std::int64_t>()},
           {"mean", row[4].as<double>()},
           {"std", row[5].is_null() ? nlohmann::json() : nlohmann::json(row[5].as<double>())},
           {"min", row[6].as<double>()},
           {"max", row[7].as<double>()}});
    }
    return {{"parameters", std::move(parameters)}};
  } catch (...) {
    rethrow_as_central("read parameters");
  }
}

nlohmann::json fleet_runs(pqxx::connection& connection, const FleetFilter& filter) {
  filter.validate();
  try {
    pqxx::read_transaction tx(connection);
    const pqxx::result r = tx.exec_params(
        std::string("SELECT s.name, s.uuid::text, r.local_id, r.id, r.procedure_name, r.status, "
                    "r.created_utc, r.started_utc, r.ended_utc, r.exit_reason, "
                    "(SELECT count(*) FROM steps t WHERE t.run_id = r.id AND t.status = "
                    "'completed'), (SELECT count(*) FROM steps t WHERE t.run_id = r.id), "
                    "(SELECT coalesce(jsonb_agg(jsonb_build_object('imu', u.imu, 'model', "
                    "u.model, 'serial', u.serial) ORDER BY u.imu), '[]'::jsonb)::text FROM "
                    "run_units u WHERE u.run_id = r.id) "
                    "FROM runs r JOIN stations s ON s.uuid = r.station WHERE ") +
            kStationMatches +
            " AND ($2 = '' OR EXISTS (SELECT 1 FROM run_units u WHERE u.run_id = r.id AND "
            "u.serial = $2)) AND r.created_utc >= $3 ORDER BY r.created_utc DESC, r.id DESC",
        filter.station, filter.serial, filter.since_utc);
    nlohmann::json runs = nlohmann::json::array();
    for (const auto& row : r) {
      runs.push_back({{"station", row[0].as<std::string>()},
                      {"station_uuid", row[1].as<std::string>()},
                      {"run", row[2].as<std::int64_t>()},
                      {"central_id", row[3].as<std::int64_t>()},
                      {"procedure", row[4].as<std::string>()},
                      {"status", row[5].as<std::string>()},
                      {"created_utc", row[6].as<std::string>()},
                      {"started_utc", text_or_null(row[7])},
                      {"ended_utc", text_or_null(row[8])},
                      {"exit_reason", text_or_null(row[9])},
                      {"steps_done", row[10].as<std::int64_t>()},
                      {"steps_total", row[11].as<std::int64_t>()},
                      {"units", nlohmann::json::parse(row[12].as<std::string>())}});
    }
    return {{"runs", std::move(runs)}};
  } catch (...) {
    rethrow_as_central("read runs");
  }
}

nlohmann::json fleet_units(pqxx::connection& connection, const FleetFilter& filter) {
  filter.validate();
  try {
    pqxx::read_transaction tx(connection);
    const pqxx::result r = tx.exec_params(
        std::string(
            "WITH unit_runs AS (SELECT u.serial, u.model, s.name AS station, r.id AS run_id, "
            "r.created_utc FROM run_units u JOIN runs r ON r.id = u.run_id JOIN stations s ON "
            "s.uuid = r.station WHERE u.serial <> '' AND ") +
            kStationMatches +
            " AND ($2 = '' OR u.serial = $2) AND r.created_utc >= $3) "
            "SELECT serial, max(model), (SELECT jsonb_agg(DISTINCT x.station)::text FROM "
            "unit_runs x WHERE x.serial = unit_runs.serial), count(DISTINCT run_id), "
            "(SELECT count(*) FROM calibrations c WHERE c.serial = unit_runs.serial), "
            "max(created_utc), "
            "(SELECT a.verdict FROM calibrations c JOIN acceptances a ON a.calibration_id = c.id "
            "WHERE c.serial = unit_runs.serial ORDER BY c.created_utc DESC, c.id DESC, "
            "a.created_utc DESC, a.id DESC LIMIT 1) "
            "FROM unit_runs GROUP BY serial ORDER BY serial",
        filter.station, filter.serial, filter.since_utc);
    nlohmann::json units = nlohmann::json::array();
    for (const auto& row : r) {
      units.push_back({{"serial", row[0].as<std::string>()},
                       {"model", row[1].as<std::string>()},
                       {"stations", nlohmann::json::parse(row[2].as<std::string>())},
                       {"runs", row[3].as<std::int64_t>()},
                       {"calibrations", row[4].as<std::int64_t>()},
                       {"last_run_utc", row[5].as<std::string>()},
                       {"latest_verdict", text_or_null(row[6])}});
    }
    return {{"units", std::move(units)}};
  } catch (...) {
    rethrow_as_central("read units");
  }
}

nlohmann::json fleet_calibrations(pqxx::connection& connection, const FleetFilter& filter) {
  filter.validate();
  CentralRecords records(connection);
  std::vector<analysis::UnitRecord> all = analysis::unit_records(records, filter.serial);
  std::vector<analysis::UnitRecord> kept;
  // The station filter compares names here; a uuid is matched through the stations table.
  std::string station_name = filter.station;
  if (!filter.station.empty()) {
    try {
      pqxx::read_transaction tx(connection);
      const pqxx::result r = tx.exec_params(
          "SELECT name FROM stations WHERE uuid::text = $1 OR name = $1 LIMIT 1", filter.station);
      station_name = r.empty() ? filter.station : r[0][0].as<std::string>();
    } catch (...) {
      rethrow_as_central("read stations");
    }
  }
  for (analysis::UnitRecord& u : all) {
    if (!filter.station.empty() && u.calibration.station != station_name) continue;
    if (u.calibration.created_utc < filter.since_utc) continue;
    kept.push_back(std::move(u));
  }
  return analysis::unit_records_json(filter.serial, kept);
}

}  // namespace calstand::fleet
