#include "factory/lot.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <map>
#include <numeric>

#include "core/error.hpp"
#include "store/acceptances.hpp"
#include "store/calibrations.hpp"

namespace calstand::analysis {
namespace {

/// Converts the median absolute deviation of normal data to its standard deviation.
constexpr double kMadToSigma = 1.4826;
/// d2 of a moving range of two: the mean moving range over d2 estimates sigma (individuals
/// chart, ASTM E2587).
constexpr double kMovingRangeD2 = 1.128;

double median_of(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

void describe(LotParameter& p, const std::vector<LotUnit>& units,
              const std::map<std::string, std::size_t>& unit_of_serial) {
  const auto& v = p.values;
  const double n = static_cast<double>(v.size());
  p.mean = std::accumulate(v.begin(), v.end(), 0.0) / n;
  double ss = 0.0;
  for (double x : v) ss += (x - p.mean) * (x - p.mean);
  p.std_dev = v.size() > 1 ? std::sqrt(ss / (n - 1.0)) : 0.0;
  p.median = median_of(v);
  std::vector<double> deviations;
  for (double x : v) deviations.push_back(std::abs(x - p.median));
  p.robust_sigma = kMadToSigma * median_of(deviations);
  p.min = *std::min_element(v.begin(), v.end());
  p.max = *std::max_element(v.begin(), v.end());
  double moving_range = 0.0;
  for (std::size_t i = 1; i < v.size(); ++i) moving_range += std::abs(v[i] - v[i - 1]);
  const double sigma_chart =
      v.size() > 1 ? moving_range / static_cast<double>(v.size() - 1) / kMovingRangeD2 : 0.0;
  p.control_lower = p.mean - 3.0 * sigma_chart;
  p.control_upper = p.mean + 3.0 * sigma_chart;
  if (v.size() < kLotMinUnitsForOutliers) return;
  for (std::size_t i = 0; i < v.size(); ++i) {
    const double deviation = v[i] - p.median;
    // All siblings equal (MAD 0): any unit off that value is infinitely far from them.
    const double z = p.robust_sigma > 0.0 ? deviation / p.robust_sigma
                     : deviation == 0.0   ? 0.0
                                          : std::copysign(INFINITY, deviation);
    if (std::abs(z) > kLotOutlierZ) {
      const LotUnit& u = units[unit_of_serial.at(p.serials[i])];
      p.outliers.push_back({p.serials[i], v[i], z, u.verdict});
    }
  }
}

// The whole number of text[at, at + digits), or -1 when those are not all digits.
int digits_at(const std::string& text, std::size_t at, std::size_t digits) {
  if (at + digits > text.size()) return -1;
  int value = 0;
  const char* first = text.data() + at;
  const auto [ptr, ec] = std::from_chars(first, first + digits, value);
  return ec == std::errc() && ptr == first + digits && value >= 0 ? value : -1;
}

}  // namespace

void check_lot_since(const std::string& since_utc, const std::string& where) {
  if (since_utc.empty()) return;
  const auto malformed = [&] {
    return core::InputError(where, fmt::format("expected a UTC date YYYY-MM-DD or time "
                                               "YYYY-MM-DDTHH:MM[:SS], got \"{}\"",
                                               since_utc));
  };
  // Fixed positions: the separators first, then every field a number in range.
  const std::size_t n = since_utc.size();
  if ((n != 10 && n != 16 && n != 19) || since_utc[4] != '-' || since_utc[7] != '-') {
    throw malformed();
  }
  const int y = digits_at(since_utc, 0, 4);
  const int m = digits_at(since_utc, 5, 2);
  const int d = digits_at(since_utc, 8, 2);
  if (y < 0 || m < 0 || d < 0) throw malformed();
  const std::chrono::year_month_day date{std::chrono::year(y), std::chrono::month(unsigned(m)),
                                         std::chrono::day(unsigned(d))};
  if (!date.ok()) throw malformed();
  if (n == 10) return;
  if (since_utc[10] != 'T' || since_utc[13] != ':') throw malformed();
  const int hour = digits_at(since_utc, 11, 2);
  const int minute = digits_at(since_utc, 14, 2);
  if (hour < 0 || hour > 23 || minute < 0 || minute > 59) throw malformed();
  if (n == 16) return;
  const int second = digits_at(since_utc, 17, 2);
  if (since_utc[16] != ':' || second < 0 || second > 59) throw malformed();
}

LotStatistics lot_statistics(store::Database& db, const std::string& since_utc) {
  store::DatabaseRecords records(db);
  return lot_statistics(records, since_utc);
}

LotStatistics lot_statistics(store::RecordSource& records, const std::string& since_utc) {
  check_lot_since(since_utc, "since");
  LotStatistics lot;
  lot.since_utc = since_utc;
  // Oldest first: a unit's later record replaces its earlier one, and the unit takes the place
  // of its newest record in the calibration order (the control chart's x).
  std::map<std::string, store::CalibrationRow> newest;
  std::vector<std::string> order;
  for (store::CalibrationRow& row : records.calibrations_since(since_utc)) {
    if (row.serial.empty()) {
      ++lot.records_without_serial;
      continue;
    }
    order.erase(std::remove(order.begin(), order.end(), row.serial), order.end());
    order.push_back(row.serial);
    newest[row.serial] = std::move(row);
  }
  std::map<std::string, std::size_t> unit_of_serial;
  std::map<std::string, std::size_t> parameter_index;
  for (const std::string& serial : order) {
    const store::CalibrationRow& row = newest.at(serial);
    LotUnit u;
    u.serial = serial;
    u.device = row.imu;
    u.calibration = row.id;
    u.run = row.run;
    u.created_utc = row.created_utc;
    u.station = row.station;
    if (const auto a = records.latest_acceptance(row.id)) u.verdict = a->verdict;
    if (u.verdict == "pass") {
      ++lot.passed;
    } else if (u.verdict == "fail") {
      ++lot.failed;
    } else if (u.verdict == "indeterminate") {
      ++lot.indeterminate;
    } else {
      ++lot.not_judged;
    }
    unit_of_serial[serial] = lot.units.size();
    lot.units.push_back(u);
    for (const auto& p : row.record.value("parameters", nlohmann::json::array())) {
      const std::string name = p.value("name", "");
      auto [it, added] = parameter_index.emplace(name, lot.parameters.size());
      if (added) {
        LotParameter first;
        first.name = name;
        first.unit = p.value("unit", "");
        lot.parameters.push_back(std::move(first));
      }
      LotParameter& lp = lot.parameters[it->second];
      lp.values.push_back(p.value("value", 0.0));
      lp.serials.push_back(serial);
    }
  }
  const std::size_t judged = lot.passed + lot.failed + lot.indeterminate;
  if (judged > 0) lot.yield = static_cast<double>(lot.passed) / static_cast<double>(judged);
  for (LotParameter& p : lot.parameters) describe(p, lot.units, unit_of_serial);
  return lot;
}

nlohmann::json to_json(const LotStatistics& lot) {
  nlohmann::json units = nlohmann::json::array();
  for (const LotUnit& u : lot.units) {
    units.push_back(
        {{"serial", u.serial},
         {"device", u.device},
         {"calibration", u.calibration},
         {"run", u.run},
         {"created_utc", u.created_utc},
         {"verdict", u.verdict.empty() ? nlohmann::json() : nlohmann::json(u.verdict)}});
    if (!u.station.empty()) units.back()["station"] = u.station;
  }
  nlohmann::json parameters = nlohmann::json::array();
  for (const LotParameter& p : lot.parameters) {
    nlohmann::json values = nlohmann::json::array();
    for (std::size_t i = 0; i < p.values.size(); ++i) {
      values.push_back({{"serial", p.serials[i]}, {"value", p.values[i]}});
    }
    nlohmann::json outliers = nlohmann::json::array();
    for (const LotOutlier& o : p.outliers) {
      outliers.push_back(
          {{"serial", o.serial},
           {"value", o.value},
           {"robust_z", std::isfinite(o.robust_z) ? nlohmann::json(o.robust_z) : nlohmann::json()},
           {"verdict", o.verdict.empty() ? nlohmann::json() : nlohmann::json(o.verdict)}});
    }
    parameters.push_back(
        {{"name", p.name},
         {"unit", p.unit},
         {"n", p.values.size()},
         {"mean", p.mean},
         {"std", p.std_dev},
         {"median", p.median},
         {"robust_sigma", p.robust_sigma},
         {"min", p.min},
         {"max", p.max},
         {"control", {{"centre", p.mean}, {"lower", p.control_lower}, {"upper", p.control_upper}}},
         {"values", values},
         {"outliers", outliers}});
  }
  return {{"since", lot.since_utc},
          {"units", units},
          {"records_without_serial", lot.records_without_serial},
          {"verdicts",
           {{"pass", lot.passed},
            {"fail", lot.failed},
            {"indeterminate", lot.indeterminate},
            {"not_judged", lot.not_judged}}},
          {"yield", lot.yield ? nlohmann::json(*lot.yield) : nlohmann::json()},
          {"parameters", parameters}};
}

}  // namespace calstand::analysis
