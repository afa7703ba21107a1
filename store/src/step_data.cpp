#include "store/step_data.hpp"

#include <SQLiteCpp/Statement.h>
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <span>
#include <utility>

#include "core/error.hpp"
#include "sql_util.hpp"
#include "store/run_store.hpp"
#include "store/sample_reader.hpp"

namespace calstand::store {
namespace {

struct TimedTable {
  double time_s = 0.0;
  TableSample state;
};

std::vector<TimedTable> read_table(SQLite::Database& db, const char* where, std::int64_t id) {
  SQLite::Statement q(
      db, fmt::format("SELECT time_s, outer_deg, inner_deg, outer_rate_dps, "
                      "inner_rate_dps FROM table_telemetry WHERE {} = ? "
                      "ORDER BY {}",
                      where, std::string_view(where) == "step_id" ? "id" : "time_s, id"));
  q.bind(1, id);
  std::vector<TimedTable> out;
  while (q.executeStep()) {
    out.push_back({q.getColumn(0).getDouble(),
                   {q.getColumn(1).getDouble(), q.getColumn(2).getDouble(),
                    q.getColumn(3).getDouble(), q.getColumn(4).getDouble()}});
  }
  return out;
}

double wrap180(double deg) {
  double w = std::fmod(deg + 180.0, 360.0);
  if (w < 0.0) w += 360.0;
  return w - 180.0;
}

// Table state at `t_s` from time-ordered telemetry of one step: linear between neighbours
// (the turn between rows resolved with the recorded rates); outside the rows' span the nearest row,
// its angles advanced at its rates (a rate step's angles keep turning; a position step's rates are
// zero).
TableSample interpolate(std::span<const TimedTable> rows, double t_s) {
  const auto after = std::lower_bound(rows.begin(), rows.end(), t_s,
                                      [](const TimedTable& r, double t) { return r.time_s < t; });
  const auto hold = [t_s](const TimedTable& r) {
    TableSample s = r.state;
    s.outer_deg = wrap180(s.outer_deg + s.outer_rate_dps * (t_s - r.time_s));
    s.inner_deg = wrap180(s.inner_deg + s.inner_rate_dps * (t_s - r.time_s));
    return s;
  };
  if (after == rows.begin()) return hold(*after);
  if (after == rows.end()) return hold(rows.back());
  const TableSample& a = std::prev(after)->state;
  const TableSample& b = after->state;
  const double span = after->time_s - std::prev(after)->time_s;
  const double f = span > 0.0 ? (t_s - std::prev(after)->time_s) / span : 0.0;
  // The turn between the rows: what the mean rate predicts, corrected by the wrapped difference
  // of the encoder readings. A fast axis turns several revolutions between rows; the rates
  // resolve how many.
  const auto turn = [span](double from_deg, double to_deg, double rate_a, double rate_b) {
    const double predicted = 0.5 * (rate_a + rate_b) * span;
    return predicted + wrap180(to_deg - from_deg - predicted);
  };
  return {
      wrap180(a.outer_deg + f * turn(a.outer_deg, b.outer_deg, a.outer_rate_dps, b.outer_rate_dps)),
      wrap180(a.inner_deg + f * turn(a.inner_deg, b.inner_deg, a.inner_rate_dps, b.inner_rate_dps)),
      a.outer_rate_dps + f * (b.outer_rate_dps - a.outer_rate_dps),
      a.inner_rate_dps + f * (b.inner_rate_dps - a.inner_rate_dps)};
}

// The rows of `run_table` (time-ordered) recorded while the step ran. Rows of the move before
// a capture must not leak into it: samples between the move's last row and the capture's first
// would get angles half-way through the move.
std::span<const TimedTable> rows_of_step(const std::vector<TimedTable>& run_table,
                                         const StepRecord& step) {
  if (!step.started_clock_s || !step.ended_clock_s) return {};
  const auto first = std::lower_bound(run_table.begin(), run_table.end(), *step.started_clock_s,
                                      [](const TimedTable& r, double t) { return r.time_s < t; });
  const auto last = std::upper_bound(first, run_table.end(), *step.ended_clock_s,
                                     [](double t, const TimedTable& r) { return t < r.time_s; });
  return {first, last};
}

TableSample commanded_table(const nlohmann::json& c) {
  return {c.value("outer_deg", c.value("outer_start_deg", 0.0)),
          c.value("inner_deg", c.value("inner_start_deg", 0.0)), c.value("outer_rate_dps", 0.0),
          c.value("inner_rate_dps", 0.0)};
}

}  // namespace

bool orientation_known(const StepRecord& step) {
  const auto it = step.commanded.find("orientation");
  return it == step.commanded.end() || *it != "unknown";
}

bool orientation_known(Database& db, std::int64_t run) {
  RunStore runs(db);
  const std::vector<StepRecord> steps = runs.load_run(run).steps;  // throws for an unknown run
  return std::all_of(steps.begin(), steps.end(),
                     [](const StepRecord& s) { return orientation_known(s); });
}

std::string choose_device(Database& db, std::int64_t run, const std::string& device) {
  const std::vector<std::string> devices = sample_devices(db, run);
  const std::string where = "run " + std::to_string(run);
  if (!device.empty()) {
    if (std::find(devices.begin(), devices.end(), device) == devices.end()) {
      throw core::InputError(where, "has no samples of device '" + device + "'");
    }
    return device;
  }
  if (devices.empty()) throw core::InputError(where, "has no samples");
  if (devices.size() > 1) {
    throw core::InputError(where, fmt::format("has samples of several IMUs ({}): choose one",
                                              fmt::join(devices, ", ")));
  }
  return devices.front();
}

namespace {

/// for_each_step_data() handing each step's data over: read_step_data() keeps it without a
/// copy of every sample (a long run's samples are hundreds of megabytes).
void for_each_owned_step_data(Database& db, std::int64_t run, const std::string& device,
                              const std::function<void(StepData&&)>& use) {
  RunStore runs(db);
  const std::vector<StepRecord> steps = runs.load_steps(run);
  const std::vector<TimedTable> run_table =
      detail::guarded("read table telemetry", [&] { return read_table(db.sql(), "run_id", run); });
  for (const StepRecord& step : steps) {
    if (step.status != StepStatus::kCompleted) continue;
    StepData data;
    data.samples = read_samples(db, run, step.index, device);
    if (data.samples.empty()) continue;
    const std::vector<TimedTable> step_table = detail::guarded(
        "read table telemetry", [&] { return read_table(db.sql(), "step_id", step.id); });
    // Imported runs hold one table row per sample, in sample order.
    const bool per_sample = step_table.size() == data.samples.size();
    const std::span<const TimedTable> rows = rows_of_step(run_table, step);
    data.table.reserve(data.samples.size());
    if (!orientation_known(step)) {
      // No encoder read anything: NaN, never zeros that would pass for a table at rest at 0.
      const double nan = std::numeric_limits<double>::quiet_NaN();
      data.table.assign(data.samples.size(), TableSample{nan, nan, nan, nan});
    }
    for (std::size_t i = data.table.size(); i < data.samples.size(); ++i) {
      data.table.push_back(per_sample      ? step_table[i].state
                           : !rows.empty() ? interpolate(rows, data.samples[i].receive_time_s)
                                           : commanded_table(step.commanded));
    }
    data.step = step;
    use(std::move(data));
  }
}

}  // namespace

void for_each_step_data(Database& db, std::int64_t run, const std::string& device,
                        const std::function<void(const StepData&)>& use) {
  for_each_owned_step_data(db, run, device, [&](StepData&& data) { use(data); });
}

std::vector<StepData> read_step_data(Database& db, std::int64_t run, const std::string& device) {
  std::vector<StepData> out;
  for_each_owned_step_data(db, run, device,
                           [&](StepData&& data) { out.push_back(std::move(data)); });
  return out;
}

}  // namespace calstand::store
