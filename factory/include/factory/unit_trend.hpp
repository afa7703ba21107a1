#pragma once
// How a unit's calibration parameters moved across its records (`calstand trend`): aging,
// storage, a shock in transport show as a drift beyond the records' own uncertainties.

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "store/database.hpp"
#include "store/record_source.hpp"

namespace calstand::analysis {

/// One record of the unit, oldest first.
struct TrendRecord {
  std::int64_t calibration = 0;
  std::int64_t run = 0;
  std::string created_utc;
  std::string verdict;  ///< latest acceptance verdict; empty when not judged
  std::string station;  ///< the station that made the record (central database only)
};

/// A parameter across the unit's records: its value and sigma in each record that fitted it
/// (records without it hold none), and the change from the first to the last record.
struct TrendParameter {
  std::string name;
  std::string unit;
  std::vector<std::optional<double>> values;  ///< per record of UnitTrend::records
  std::vector<std::optional<double>> sigmas;
  double change = 0.0;        ///< last - first value where both exist
  double change_sigma = 0.0;  ///< sqrt(sigma_first^2 + sigma_last^2)
  /// change / change_sigma: beyond about 3 the unit moved more than its calibrations can tell
  /// apart; none with fewer than two records of the parameter or no uncertainty.
  std::optional<double> change_z;
};

struct UnitTrend {
  std::string serial;
  std::vector<TrendRecord> records;
  std::vector<TrendParameter> parameters;  ///< in the order they first appear
};

/// The trend of unit `serial` over every record of it. Throws core::InputError naming the
/// serial when it has no record.
UnitTrend unit_trend(store::RecordSource& records, const std::string& serial);
/// The same on a station's own file.
UnitTrend unit_trend(store::Database& db, const std::string& serial);

/// `{"serial", "records": [{"calibration", "run", "created_utc", "verdict", "station" (central
///   database only)}], "parameters":
///   [{"name", "unit", "values": [value|null...], "sigmas": [...], "change", "change_sigma",
///   "change_z"}]}`
nlohmann::json to_json(const UnitTrend& trend);

}  // namespace calstand::analysis
