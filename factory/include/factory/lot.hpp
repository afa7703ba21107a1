#pragma once
// Lot statistics across every unit calibrated (`calstand lot`): the distribution of each
// parameter, the units far from their siblings, the yield, and a control chart per parameter.

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "store/database.hpp"
#include "store/record_source.hpp"

namespace calstand::analysis {

/// A unit counts once in a lot, with its newest record.
struct LotUnit {
  std::string serial;
  std::string device;  ///< the slot it was calibrated in
  std::int64_t calibration = 0;
  std::int64_t run = 0;
  std::string created_utc;
  std::string verdict;  ///< its record's latest acceptance verdict; empty when not judged
  std::string station;  ///< the station that made the record (central database only)
};

/// A unit whose value lies far from its siblings' (robust z beyond kLotOutlierZ).
struct LotOutlier {
  std::string serial;
  double value = 0.0;
  double robust_z = 0.0;  ///< (value - median) / (1.4826 MAD)
  std::string verdict;    ///< it may pass and still be worth a look
};

/// Units further than this many robust sigmas from the lot's median are flagged.
inline constexpr double kLotOutlierZ = 4.0;
/// Fewer units than this have no meaningful spread: nobody is flagged.
inline constexpr std::size_t kLotMinUnitsForOutliers = 3;

/// One parameter across the lot, in the record's unit.
struct LotParameter {
  std::string name;
  std::string unit;
  std::vector<double> values;        ///< per unit, in calibration order (the chart's x)
  std::vector<std::string> serials;  ///< the unit of each value
  double mean = 0.0;
  double std_dev = 0.0;  ///< sample standard deviation (n - 1); 0 for one unit
  double median = 0.0;
  double robust_sigma = 0.0;  ///< 1.4826 MAD: the spread the outliers themselves do not inflate
  double min = 0.0;
  double max = 0.0;
  /// Individuals control chart (Shewhart): centre = mean, limits = mean +- 3 * mean moving
  /// range / 1.128. Limits equal the centre for fewer than two units.
  double control_lower = 0.0;
  double control_upper = 0.0;
  std::vector<LotOutlier> outliers;
};

struct LotStatistics {
  std::string since_utc;                   ///< the lot's start (empty: every record)
  std::vector<LotUnit> units;              ///< in calibration order
  std::size_t records_without_serial = 0;  ///< left out: nobody knows which unit they were
  std::size_t passed = 0;
  std::size_t failed = 0;
  std::size_t indeterminate = 0;
  std::size_t not_judged = 0;
  /// passed / judged units; none when no unit was judged.
  std::optional<double> yield;
  std::vector<LotParameter> parameters;  ///< in the order they first appear
};

/// Checks the start of a lot as `calstand lot --since` and GET /lot?since= take it: a UTC date
/// YYYY-MM-DD, or a UTC time YYYY-MM-DDTHH:MM[:SS]; empty: every record. Records' times are
/// compared with it as text, so any other form (a slash, a missing zero, a time zone) would
/// select another lot than it says without a word. Throws core::InputError naming `where`.
void check_lot_since(const std::string& since_utc, const std::string& where);

/// The lot of every unit (serial) calibrated at or after `since_utc` (check_lot_since; empty:
/// all), each with its newest record. Throws core::InputError naming `since` for a malformed
/// start.
LotStatistics lot_statistics(store::RecordSource& records, const std::string& since_utc);
/// The same on a station's own file.
LotStatistics lot_statistics(store::Database& db, const std::string& since_utc);

/// `{"since", "units": [{"serial", "device", "calibration", "run", "created_utc", "verdict",
///   "station" (central database only)}], "records_without_serial", "verdicts": {"pass", "fail",
///   "indeterminate", "not_judged"}, "yield", "parameters": [{"name", "unit", "n", "mean",
///   "std", "median", "robust_sigma", "min", "max", "control": {"centre", "lower", "upper"},
///   "values": [{"serial", "value"}], "outliers": [{"serial", "value", "robust_z", "verdict"}]}]}`
nlohmann::json to_json(const LotStatistics& lot);

/// The lot as an HTML page: yield, the parameter table with outliers, and a control chart per
/// parameter (gnuplot SVG). Throws core::InputError naming gnuplot when it is missing.
std::string lot_html(const LotStatistics& lot);

}  // namespace calstand::analysis
