#include "analysis/run_series.hpp"

#include <fmt/format.h>

#include <optional>

#include "analysis/run_model.hpp"
#include "store/run_store.hpp"
#include "store/sample_reader.hpp"
#include "store/step_data.hpp"

namespace calstand::analysis {
namespace {

// Index of an IMU channel in series_signals() (gx..az, temp_c), or nullopt for a table signal.
std::optional<int> imu_channel_of(const std::string& signal) {
  const auto& all = series_signals();
  for (int i = 0; i < 7; ++i) {
    if (signal == all[static_cast<std::size_t>(i)].name) return i;
  }
  return std::nullopt;
}

double imu_value(const core::ImuSample& s, int channel) {
  if (channel < 3) return s.gyro_dps[channel];
  if (channel < 6) return s.accel_mps2[channel - 3];
  return s.temperature_c;
}

double table_value(const store::TableSample& t, const std::string& signal) {
  if (signal == "table_outer_deg") return t.outer_deg;
  if (signal == "table_inner_deg") return t.inner_deg;
  if (signal == "table_outer_rate_dps") return t.outer_rate_dps;
  return t.inner_rate_dps;
}

}  // namespace

const std::vector<SeriesSignal>& series_signals() {
  static const std::vector<SeriesSignal> kSignals = {
      {"gx", "deg/s", "measured angular rate, body x"},
      {"gy", "deg/s", "measured angular rate, body y"},
      {"gz", "deg/s", "measured angular rate, body z"},
      {"ax", "m/s^2", "measured specific force, body x"},
      {"ay", "m/s^2", "measured specific force, body y"},
      {"az", "m/s^2", "measured specific force, body z"},
      {"temp_c", "degC", "the IMU's internal temperature"},
      {"table_outer_deg", "deg", "table outer axis angle at each sample"},
      {"table_inner_deg", "deg", "table inner axis angle at each sample"},
      {"table_outer_rate_dps", "deg/s", "table outer axis rate at each sample"},
      {"table_inner_rate_dps", "deg/s", "table inner axis rate at each sample"},
  };
  return kSignals;
}

RunSeries run_series(store::Database& db, std::int64_t run, const SeriesRequest& request) {
  const SeriesSignal* signal = nullptr;
  std::string known;
  for (const auto& s : series_signals()) {
    if (request.signal == s.name) signal = &s;
    known += (known.empty() ? "" : ", ") + std::string(s.name);
  }
  if (signal == nullptr) {
    throw core::InputError("signal",
                           fmt::format("unknown signal '{}' (known: {})", request.signal, known));
  }
  if (request.max_points < 2) throw core::InputError("max_points", "must be at least 2");
  if (!(request.from_s < request.to_s)) {
    throw core::InputError("from_s/to_s", "from_s must be before to_s");
  }
  store::RunStore runs(db);
  try {
    runs.run_status(run);  // throws for an unknown run
  } catch (const core::InputError& e) {
    throw RunNotFound(e.where(), fmt::format("no such run"));
  }
  if (store::sample_devices(db, run).empty()) {
    throw NothingToFit(fmt::format("run {}", run), "has no samples");
  }
  RunSeries out;
  out.signal = signal->name;
  out.unit = signal->unit;
  out.device = store::choose_device(db, run, request.device);
  Downsampler down(request.max_points);
  std::optional<double> origin_s;  // the run's first sample [s, station clock]
  const auto add = [&](double receive_time_s, double value) {
    if (!origin_s) origin_s = receive_time_s;
    const double t_s = receive_time_s - *origin_s;
    if (t_s >= request.from_s && t_s <= request.to_s) down.add(t_s, value);
  };
  if (const auto channel = imu_channel_of(out.signal)) {
    for (const auto& step : runs.load_steps(run)) {
      store::for_each_chunk(db, run, step.index, out.device,
                            [&](const store::ChunkInfo&, std::span<const core::ImuSample> chunk) {
                              for (const auto& s : chunk)
                                add(s.receive_time_s, imu_value(s, *channel));
                            });
    }
  } else {
    store::for_each_step_data(db, run, out.device, [&](const store::StepData& step) {
      for (std::size_t i = 0; i < step.samples.size(); ++i) {
        add(step.samples[i].receive_time_s, table_value(step.table[i], out.signal));
      }
    });
  }
  out.series = down.result();
  return out;
}

nlohmann::json to_json(const RunSeries& s) {
  return {{"signal", s.signal},         {"unit", s.unit},      {"t_s", s.series.t_s},
          {"min", s.series.min},        {"max", s.series.max}, {"mean", s.series.mean},
          {"samples", s.series.samples}};
}

}  // namespace calstand::analysis
